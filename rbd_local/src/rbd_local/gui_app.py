"""``rbd-gui``: the operator window, connected to the robot through :mod:`rbd_local.link`.

With ``--camera``/``--video``/``--images``/``--robot-camera`` it also runs gesture recognition
in the same process (headless, in a background thread), shows the last gesture in the window,
and its Teach panel can teach new gestures (the model file: the configured ``model``, else the
user's, see ``rbd-teach``).
"""

import argparse
import logging
import sys
import threading
import time

from rbd_local.gestures.config import load_config


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of rbd-gui."""
    p = argparse.ArgumentParser(prog="rbd-gui", description=__doc__)
    p.add_argument("--config", help="YAML configuration (default: the packaged one)")
    p.add_argument("--host", help="rbd_bridge host (overrides the configuration)")
    p.add_argument("--port", type=int, help="rbd_bridge port (overrides the configuration)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--camera", type=int, help="also recognise gestures from this camera")
    src.add_argument("--video", help="also recognise gestures from this video file")
    src.add_argument("--images", help="also recognise gestures from these images")
    src.add_argument("--robot-camera", nargs="?", const="", metavar="TOPIC",
                     help="also recognise gestures from the robot's camera through the bridge "
                          "(default topic /zed2/zed_node/left/image_rect_color/compressed)")
    p.add_argument("--camera-max-fps", type=float, default=30.0,
                   help="with --robot-camera: most frames per second the bridge sends (0: all)")
    p.add_argument("--screenshot", help="save a screenshot of the window to this PNG, then quit")
    p.add_argument("--screenshot-delay", type=float, default=3.0,
                   help="seconds before the screenshot (with --video/--images: at least until the clip "
                        "has been played, at most %d s more)" % CLIP_WAIT_S)
    return p


SCORES_PERIOD_S = 0.1  # the Teach panel's confidence bars: at most 10 updates per second
CLIP_WAIT_S = 120  # --screenshot with a recorded clip: longest wait for its end after the delay


def _run_gestures(source: object, cfg: dict, link: object, gui: object, stop: threading.Event,
                  desk: object) -> None:
    from rbd_local.gestures.model import GestureModel
    from rbd_local.gestures.pipeline import GesturePipeline

    if not source.live:  # a recorded clip is replayed for the robot, not before it listens
        while not stop.is_set() and not link.wait_connected(1.0):
            pass
    pipeline = GesturePipeline(GestureModel.load(cfg["model"]), cfg["gestures"], send=link.send_gesture,
                               threshold=cfg["threshold"], min_consecutive=cfg["min_consecutive"],
                               cooldown_s=cfg["cooldown_s"], model_complexity=cfg["model_complexity"])
    next_scores = 0.0
    desk.step(pipeline)  # the Teach panel lists the model's taught gestures before the first frame
    try:
        for t, frame in source:
            if stop.is_set():
                break
            desk.step(pipeline)
            result = pipeline.process(t, frame)
            if hasattr(source, "frame_done"):
                source.frame_done()
            if result.command:
                gui.post_gesture(result.decision.label, result.command, result.decision.confidence)
            now = time.monotonic()
            if now >= next_scores:
                next_scores = now + SCORES_PERIOD_S
                gui.teach_panel.post_scores(result.decision.scores or {})
    finally:
        source.close()
        pipeline.close()


def main(argv: list[str] = None) -> int:
    """Open the operator window.

    Returns:
        Process exit code.
    """
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    try:
        cfg = load_config(args.config)
    except (OSError, ValueError) as exc:
        print("rbd-gui: %s" % exc, file=sys.stderr)
        return 2
    source = None
    camera = {}
    if args.robot_camera is not None:
        from rbd_local.gestures.robot_camera import RobotCameraSource
        from rbd_local.link import CAMERA_TOPIC

        if not args.camera_max_fps >= 0:
            print("rbd-gui: --camera-max-fps must be >= 0", file=sys.stderr)
            return 2
        source = RobotCameraSource()
        camera = {"on_camera": source.push, "camera_topic": args.robot_camera or CAMERA_TOPIC,
                  "camera_throttle_ms": int(1000.0 / args.camera_max_fps) if args.camera_max_fps else 0}
    elif args.camera is not None or args.video or args.images:
        from rbd_local.gestures.sources import FrameSource

        try:
            source = FrameSource(camera=args.camera, video=args.video, images=args.images, realtime=True)
        except (OSError, ValueError) as exc:
            print("rbd-gui: %s" % exc, file=sys.stderr)
            return 2
    import customtkinter as ctk

    from rbd_local.gestures.teach import TeachDesk
    from rbd_local.gui.app import OperatorGui
    from rbd_local.link import RobotLink

    root = ctk.CTk()
    holder = {}
    try:
        link = RobotLink(
            args.host or cfg["bridge"]["host"],
            args.port or cfg["bridge"]["port"],
            on_status=lambda s: holder["gui"].post_status(s),
            on_state=lambda s: holder["gui"].post_state(s),
            on_path_queue=lambda n: holder["gui"].post_path_queue(n),
            on_connection=lambda up: holder["gui"].post_connection(up),
            on_preflight=lambda r: holder["gui"].post_preflight(r),
            **camera,
        )
    except ValueError as exc:
        print("rbd-gui: %s" % exc, file=sys.stderr)
        return 2
    desk = TeachDesk(cfg["teach_model"]) if source is not None else None
    gui = holder["gui"] = OperatorGui(
        root, link, teach_desk=desk, mapped_tricks=tuple(cfg["gestures"].values()),
        no_camera_hint="no camera in this window: start rbd-gui with --camera N, --robot-camera or --video FILE "
                       "to teach gestures")
    link.start()
    stop = threading.Event()
    worker = None
    if source is not None:
        worker = threading.Thread(target=_run_gestures, args=(source, cfg, link, gui, stop, desk), daemon=True)
        worker.start()
    if args.screenshot:
        clip = worker is not None and not source.live
        give_up = time.monotonic() + args.screenshot_delay + CLIP_WAIT_S

        def shot() -> None:
            if clip and worker.is_alive() and time.monotonic() < give_up:
                root.after(200, shot)  # the window as it is after the clip (its gestures sent)
                return
            from rbd_local.gui.screenshot import save_window

            save_window(root, args.screenshot)
            root.destroy()

        root.after(int(1000 * args.screenshot_delay), shot)
    try:
        root.mainloop()
    finally:
        stop.set()
        link.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
