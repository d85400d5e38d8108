"""``rbd-gui``: the operator window, connected to the robot through :mod:`rbd_local.link`.

With ``--camera``/``--video``/``--images`` it also runs gesture recognition in the same
process (headless, in a background thread) and shows the last gesture in the window.
"""

import argparse
import logging
import sys
import threading

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
    p.add_argument("--screenshot", help="save a screenshot of the window to this PNG, then quit")
    p.add_argument("--screenshot-delay", type=float, default=3.0, help="seconds before the screenshot")
    return p


def _run_gestures(source: object, cfg: dict, link: object, gui: object, stop: threading.Event) -> None:
    from rbd_local.gestures.model import GestureModel
    from rbd_local.gestures.pipeline import GesturePipeline

    if not source.live:
        link.wait_connected(5.0)  # a recorded clip is replayed for the robot, not before it listens
    pipeline = GesturePipeline(GestureModel.load(cfg["model"]), cfg["gestures"], send=link.send_gesture,
                               threshold=cfg["threshold"], min_consecutive=cfg["min_consecutive"],
                               cooldown_s=cfg["cooldown_s"], model_complexity=cfg["model_complexity"])
    try:
        for t, frame in source:
            if stop.is_set():
                break
            result = pipeline.process(t, frame)
            if result.command:
                gui.post_gesture(result.decision.label, result.command, result.decision.confidence)
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
    if args.camera is not None or args.video or args.images:
        from rbd_local.gestures.sources import FrameSource

        try:
            source = FrameSource(camera=args.camera, video=args.video, images=args.images, realtime=True)
        except (OSError, ValueError) as exc:
            print("rbd-gui: %s" % exc, file=sys.stderr)
            return 2
    import customtkinter as ctk

    from rbd_local.gui.app import OperatorGui
    from rbd_local.link import RobotLink

    root = ctk.CTk()
    holder = {}
    link = RobotLink(
        args.host or cfg["bridge"]["host"],
        args.port or cfg["bridge"]["port"],
        on_status=lambda s: holder["gui"].post_status(s),
        on_state=lambda s: holder["gui"].post_state(s),
        on_path_queue=lambda n: holder["gui"].post_path_queue(n),
        on_connection=lambda up: holder["gui"].post_connection(up),
    )
    gui = holder["gui"] = OperatorGui(root, link)
    link.start()
    stop = threading.Event()
    if source is not None:
        threading.Thread(target=_run_gestures, args=(source, cfg, link, gui, stop), daemon=True).start()
    if args.screenshot:
        def shot() -> None:
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
