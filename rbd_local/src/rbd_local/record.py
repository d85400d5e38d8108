"""``rbd-record``: record labelled hand key-point sequences to ``.npz`` for ``rbd-train``.

Record one performance of one gesture per file (a little still time before and after is
fine), or any length of non-gesture motion with the label ``none``::

    rbd-record --label swipe_right --seconds 3 --out rec/swipe_right_001.npz
    rbd-record --label none --video visitors.avi --out rec/none_visitors.npz
"""

import argparse
import sys

import numpy as np

from rbd_local.gestures.synthetic import CLASSES


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of rbd-record."""
    p = argparse.ArgumentParser(prog="rbd-record", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--label", required=True, help="gesture class (%s) or another class name" % ", ".join(CLASSES))
    p.add_argument("--out", required=True, help="output .npz")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--camera", type=int, default=None, help="OpenCV camera index (default 0)")
    src.add_argument("--video", help="video file")
    src.add_argument("--images", help="directory or glob of images")
    p.add_argument("--fps", type=float, default=30.0, help="frame rate of an image sequence")
    p.add_argument("--seconds", type=float, default=0.0, help="stop after this long (0: until the end / q)")
    p.add_argument("--headless", action="store_true", help="no preview window")
    p.add_argument("--model-complexity", type=int, default=0, choices=(0, 1), help="MediaPipe model")
    return p


def main(argv: list[str] = None) -> int:
    """Record and save.

    Returns:
        Process exit code.
    """
    args = build_parser().parse_args(argv)
    if not args.label.strip():
        print("rbd-record: --label must not be empty", file=sys.stderr)
        return 2
    from rbd_local.gestures.detector import HandDetector
    from rbd_local.gestures.overlay import draw_overlay
    from rbd_local.gestures.sources import FrameSource
    from rbd_local.recording import save_recording

    try:
        if args.video or args.images:
            source = FrameSource(video=args.video, images=args.images, fps=args.fps)
        else:
            source = FrameSource(camera=args.camera if args.camera is not None else 0)
    except (OSError, ValueError) as exc:
        print("rbd-record: %s" % exc, file=sys.stderr)
        return 2
    cv2 = None
    if not args.headless:
        import cv2
    times, kps = [], []
    size = (0, 0)
    with HandDetector(model_complexity=args.model_complexity) as det:
        try:
            for t, frame in source:
                if args.seconds and t > args.seconds:
                    break
                size = (frame.shape[1], frame.shape[0])
                found = det.detect(frame)
                times.append(t)
                kps.append(found[0] if found is not None else np.full((21, 3), np.nan))
                if cv2 is not None:
                    view = draw_overlay(frame, found[0] if found else None, "REC " + args.label, 1.0)
                    cv2.imshow("rbd-record", view)
                    if cv2.waitKey(1) & 0xFF in (27, ord("q")):
                        break
        except KeyboardInterrupt:
            pass
        finally:
            source.close()
            if cv2 is not None:
                cv2.destroyAllWindows()
    if not times:
        print("rbd-record: no frames", file=sys.stderr)
        return 2
    kp = np.stack(kps)
    save_recording(args.out, args.label, np.array(times), kp, size)
    seen = int(np.isfinite(kp[:, 0, 0]).sum())
    print("saved %s: %d frames, hand in %d, label %r" % (args.out, len(times), seen, args.label))
    return 0


if __name__ == "__main__":
    sys.exit(main())
