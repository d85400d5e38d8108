"""``rbd-gesture``: recognise hand gestures and send the mapped trick to the robot.

Frames come from a webcam, a video file, images, or the robot's own camera through the
bridge (``--robot-camera``: the ZED2's left image, compressed, as in the thesis' attentive
pose, where the robot turns its camera towards the visitor).
"""

import argparse
import json
import logging
import sys
import threading
import time

from rbd_local.gestures.config import load_config
from rbd_local.gestures.model import GestureModel


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of rbd-gesture."""
    p = argparse.ArgumentParser(prog="rbd-gesture", description=__doc__)
    src = p.add_mutually_exclusive_group()
    src.add_argument("--camera", type=int, default=None, help="OpenCV camera index (default 0)")
    src.add_argument("--video", help="video file instead of a camera")
    src.add_argument("--images", help="directory or glob of images instead of a camera")
    src.add_argument("--robot-camera", nargs="?", const="", metavar="TOPIC",
                     help="the robot's camera through the bridge (sensor_msgs/CompressedImage; default topic "
                          "/zed2/zed_node/left/image_rect_color/compressed)")
    p.add_argument("--camera-max-fps", type=float, default=30.0,
                   help="with --robot-camera: most frames per second the bridge sends (0: all)")
    p.add_argument("--max-seconds", type=float, default=0.0, help="stop after this many seconds (0: no limit)")
    p.add_argument("--stats", action="store_true",
                   help="print a last JSON line with frame rate and latencies (robot camera: from its stamps)")
    p.add_argument("--fps", type=float, default=30.0, help="frame rate of an image sequence")
    p.add_argument("--realtime", action="store_true", help="play a video or image sequence at its frame rate")
    p.add_argument("--config", help="YAML configuration (default: the packaged one)")
    p.add_argument("--model", help="gesture model .npz (overrides the configuration)")
    p.add_argument("--threshold", type=float, help="confidence threshold (overrides model and configuration)")
    p.add_argument("--host", help="rbd_bridge host (overrides the configuration)")
    p.add_argument("--port", type=int, help="rbd_bridge port (overrides the configuration)")
    p.add_argument("--no-link", action="store_true", help="do not connect to the robot (print gestures only)")
    p.add_argument("--headless", action="store_true", help="no overlay window")
    p.add_argument("--max-frames", type=int, default=0, help="stop after this many frames (0: run to the end)")
    return p


def main(argv: list[str] = None) -> int:
    """Run the gesture recogniser; one JSON line per sent gesture on stdout.

    Returns:
        Process exit code.
    """
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    try:
        cfg = load_config(args.config)
        model = GestureModel.load(args.model or cfg["model"])
    except (OSError, ValueError) as exc:
        print("rbd-gesture: %s" % exc, file=sys.stderr)
        return 2
    from rbd_local.gestures.pipeline import GesturePipeline
    from rbd_local.gestures.sources import FrameSource

    robot_camera = args.robot_camera is not None
    if robot_camera and args.no_link:
        print("rbd-gesture: --robot-camera needs the link to the robot (drop --no-link)", file=sys.stderr)
        return 2
    if not args.camera_max_fps >= 0:
        print("rbd-gesture: --camera-max-fps must be >= 0", file=sys.stderr)
        return 2
    try:
        if robot_camera:
            from rbd_local.gestures.robot_camera import RobotCameraSource

            source = RobotCameraSource()
        elif args.video or args.images:
            source = FrameSource(video=args.video, images=args.images, fps=args.fps, realtime=args.realtime)
        else:
            source = FrameSource(camera=args.camera if args.camera is not None else 0)
    except (OSError, ValueError) as exc:
        print("rbd-gesture: %s" % exc, file=sys.stderr)
        return 2
    link = None
    if not args.no_link:
        from rbd_local.link import CAMERA_TOPIC, RobotLink

        camera = {}
        if robot_camera:
            camera = {"on_camera": source.push, "camera_topic": args.robot_camera or CAMERA_TOPIC,
                      "camera_throttle_ms": int(1000.0 / args.camera_max_fps) if args.camera_max_fps else 0}
        try:
            link = RobotLink(args.host or cfg["bridge"]["host"], args.port or cfg["bridge"]["port"], **camera).start()
        except ValueError as exc:
            print("rbd-gesture: %s" % exc, file=sys.stderr)
            return 2
    pipeline = GesturePipeline(
        model,
        cfg["gestures"],
        send=link.send_gesture if link is not None else None,
        threshold=args.threshold if args.threshold is not None else cfg["threshold"],
        min_consecutive=cfg["min_consecutive"],
        cooldown_s=cfg["cooldown_s"],
        model_complexity=cfg["model_complexity"],
    )
    if pipeline.unmapped:
        logging.warning("gestures without a command (never sent): %s", ", ".join(pipeline.unmapped))
    cv2 = None
    if not args.headless:
        import cv2
    frames = 0
    started = time.monotonic()
    if args.max_seconds > 0 and robot_camera:
        timer = threading.Timer(args.max_seconds, source.close)  # a live source may wait for frames
        timer.daemon = True
        timer.start()
    try:
        for t, frame in source:
            result = pipeline.process(t, frame)
            frames += 1
            if robot_camera:
                source.frame_done()
            if result.command:
                print(json.dumps({"t": round(t, 3), "gesture": result.decision.label, "command": result.command,
                                  "confidence": round(result.decision.confidence, 3),
                                  "linked": bool(link is not None and link.connected)}), flush=True)
            if cv2 is not None:
                cv2.imshow("rbd-gesture", pipeline.annotate(frame, result))
                if cv2.waitKey(1) & 0xFF in (27, ord("q")):
                    break
            if args.max_frames and frames >= args.max_frames:
                break
            if args.max_seconds > 0 and time.monotonic() - started >= args.max_seconds:
                break
    except KeyboardInterrupt:
        pass
    finally:
        elapsed = time.monotonic() - started
        logging.info("%d frames in %.1f s (%.1f fps)", frames, elapsed, frames / elapsed if elapsed > 0 else 0.0)
        source.close()
        if args.stats:
            stats = {"frames": frames, "seconds": round(elapsed, 2),
                     "fps": round(frames / elapsed, 2) if elapsed > 0 else 0.0}
            if robot_camera:
                stats["robot_camera"] = source.stats()
            print(json.dumps({"stats": stats}), flush=True)
        pipeline.close()
        if link is not None:
            link.stop()
        if cv2 is not None:
            cv2.destroyAllWindows()
    return 0


if __name__ == "__main__":
    sys.exit(main())
