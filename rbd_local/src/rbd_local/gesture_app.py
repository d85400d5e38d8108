"""``rbd-gesture``: recognise hand gestures and send the mapped trick to the robot."""

import argparse
import json
import logging
import sys
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

    try:
        if args.video or args.images:
            source = FrameSource(video=args.video, images=args.images, fps=args.fps, realtime=args.realtime)
        else:
            source = FrameSource(camera=args.camera if args.camera is not None else 0)
    except (OSError, ValueError) as exc:
        print("rbd-gesture: %s" % exc, file=sys.stderr)
        return 2
    link = None
    if not args.no_link:
        from rbd_local.link import RobotLink

        link = RobotLink(args.host or cfg["bridge"]["host"], args.port or cfg["bridge"]["port"]).start()
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
    try:
        for t, frame in source:
            result = pipeline.process(t, frame)
            frames += 1
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
    except KeyboardInterrupt:
        pass
    finally:
        elapsed = time.monotonic() - started
        logging.info("%d frames in %.1f s (%.1f fps)", frames, elapsed, frames / elapsed if elapsed > 0 else 0.0)
        source.close()
        pipeline.close()
        if link is not None:
            link.stop()
        if cv2 is not None:
            cv2.destroyAllWindows()
    return 0


if __name__ == "__main__":
    sys.exit(main())
