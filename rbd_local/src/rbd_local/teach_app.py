"""``rbd-teach``: teach a new gesture from a few shows, list, forget or undo taught gestures.

Live (camera or video): ``--shows`` times "get ready", then "show it now" for 2 s; the
gesture is added to the model file as soon as the last good show is in::

    rbd-teach --name checkmark --trick bow                 # camera 0, overlay window
    rbd-teach --name checkmark --trick bow --clips s1.avi s2.avi s3.avi s4.avi s5.avi   # one show per file

With ``--clips`` at least 4 of 5 files (in general 80 %, at least 3) must give a usable show,
else nothing is taught and the exit code is 1 ("usable 3 of 5, need 4", with the files to redo).
    rbd-teach --list
    rbd-teach --forget checkmark
    rbd-teach --undo                                       # back to the file before the last change

The model file is the configured ``model`` or, when none is configured, the user's model
(``$XDG_DATA_HOME/rbd_local/gesture_model.npz``), which rbd-gesture and rbd-gui then load.
"""

import argparse
import json
import logging
import os
import sys

import numpy as np

from rbd_local.gestures.config import load_config
from rbd_local.gestures.fewshot import MIN_SHOWS
from rbd_local.gestures.model import GestureModel


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of rbd-teach."""
    p = argparse.ArgumentParser(prog="rbd-teach", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--name", help="name of the gesture to teach")
    what.add_argument("--list", action="store_true", help="list the taught gestures")
    what.add_argument("--forget", metavar="NAME", help="remove a taught gesture")
    what.add_argument("--undo", action="store_true", help="restore the model file before its last change")
    p.add_argument("--trick", help="trick the taught gesture triggers (a trick of rbd_navigation's YAML)")
    p.add_argument("--shows", type=int, default=5, help="good shows needed (3..5 recommended)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--camera", type=int, default=None, help="OpenCV camera index (default 0)")
    src.add_argument("--video", help="video file with the shows one after another")
    src.add_argument("--clips", nargs="+", help="video files with one show each")
    p.add_argument("--force", action="store_true", help="teach even if the shows look like a known gesture")
    p.add_argument("--headless", action="store_true", help="no window")
    p.add_argument("--config", help="YAML configuration (default: the packaged one)")
    p.add_argument("--model", help="model file to change (default: see above)")
    return p


def needed_shows(given: int) -> int:
    """Usable shows ``rbd-teach --clips`` needs of ``given`` files: 4 of 5 (at least 3, one in five may fail)."""
    return max(MIN_SHOWS, int(np.ceil(0.8 * given)))


def _clip_windows(model: GestureModel, paths: list, complexity: int) -> tuple:
    """One show window per file; the files without one, each with the reason."""
    from rbd_local.gestures.detector import HandDetector
    from rbd_local.gestures.sources import FrameSource
    from rbd_local.gestures.teach import extract_show, show_problem

    windows, bad = [], []
    with HandDetector(model_complexity=complexity) as det:
        for path in paths:
            source = FrameSource(video=path)
            times, kps = [], []
            try:
                for t, frame in source:
                    frame_kps = np.full((det.max_hands, 21, 3), np.nan)
                    for i, (pts, _score) in enumerate(det.detect_hands(frame)[:det.max_hands]):
                        frame_kps[i] = pts
                    times.append(t)
                    kps.append(frame_kps)
            finally:
                source.close()
            det.detect_hands(np.zeros((48, 64, 3), np.uint8))  # lose the hand: the next clip starts afresh
            w = extract_show(np.array(times), np.array(kps), model.window_s, model.samples) if times else None
            if w is None:
                why = show_problem(np.array(times), np.array(kps), model.window_s) if times else "no frames"
                bad.append((path, why))
            else:
                windows.append(w)
    return (np.stack(windows) if windows else np.empty((0, model.samples, 21, 3))), bad


def _live(model: GestureModel, args: argparse.Namespace, cfg: dict) -> int:
    from rbd_local.gestures.pipeline import GesturePipeline
    from rbd_local.gestures.sources import FrameSource
    from rbd_local.gestures.teach import TeachSession

    source = FrameSource(video=args.video) if args.video else FrameSource(camera=args.camera or 0)
    pipe = GesturePipeline(model, {}, model_complexity=cfg["model_complexity"])
    session = TeachSession(model, args.name, args.trick, shows=args.shows, force=args.force)
    pipe.start_teach(session)
    cv2 = None if args.headless else __import__("cv2")
    last = ""
    try:
        for t, frame in source:
            result = pipe.process(t, frame)
            if session.message != last:
                last = session.message
                print(last, flush=True)
            if cv2 is not None:
                cv2.imshow("rbd-teach", pipe.annotate(frame, result))
                if cv2.waitKey(1) & 0xFF in (27, ord("q")):
                    break
            if not session.active:
                break
    finally:
        source.close()
        pipe.close()
        if cv2 is not None:
            cv2.destroyAllWindows()
    return 0 if session.phase == "done" else 1


def main(argv: list[str] = None) -> int:
    """Teach, list, forget or undo.

    Returns:
        Process exit code (0 ok, 1 not taught, 2 usage or file error).
    """
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    try:
        cfg = load_config(args.config)
        path = args.model or cfg["teach_model"]
        source_model = path if os.path.isfile(path) else cfg["model"]
        model = GestureModel.load(source_model)
    except (OSError, ValueError) as exc:
        print("rbd-teach: %s" % exc, file=sys.stderr)
        return 2
    if args.list:
        for name in model.taught.names:
            print("%s -> %s (%d shows)" % (name, model.taught.commands[name], len(model.taught.windows[name])))
        print("model %s, revision %d" % (source_model, model.revision))
        return 0
    if args.undo:
        from rbd_local.gestures.teach import restore_previous

        try:
            restore_previous(path)
        except FileNotFoundError as exc:
            print("rbd-teach: %s" % exc, file=sys.stderr)
            return 2
        print("restored %s to revision %d" % (path, GestureModel.load(path).revision))
        return 0
    if args.forget:
        try:
            model.forget(args.forget)
        except KeyError as exc:
            print("rbd-teach: %s" % exc.args[0], file=sys.stderr)
            return 2
        model.save(path, keep_previous=True)
        print("forgot %s; saved %s (revision %d)" % (args.forget, path, model.revision))
        return 0
    if not args.trick:
        print("rbd-teach: --name needs --trick", file=sys.stderr)
        return 2
    if args.name in model.classes:
        print("rbd-teach: %r is a built-in gesture; choose another name" % args.name, file=sys.stderr)
        return 2
    if args.clips:
        if len(args.clips) < MIN_SHOWS:
            print("rbd-teach: --clips needs at least %d files (one show each)" % MIN_SHOWS, file=sys.stderr)
            return 2
        windows, bad = _clip_windows(model, args.clips, cfg["model_complexity"])
        for path, why in bad:
            print("no usable show in %s: %s" % (path, why), file=sys.stderr)
        need = needed_shows(len(args.clips))
        if len(windows) < need:
            print("rbd-teach: not taught: usable %d of %d, need %d (show the gesture again in: %s)"
                  % (len(windows), len(args.clips), need, ", ".join(p for p, _ in bad)), file=sys.stderr)
            return 1
        try:
            report = model.teach(args.name, args.trick, windows, force=args.force)
        except ValueError as exc:
            print("rbd-teach: not taught: %s" % exc, file=sys.stderr)
            return 1
        print(json.dumps({k: report[k] for k in ("name", "command", "shows", "built_in", "taught")}))
    else:
        code = _live(model, args, cfg)
        if code:
            return code
    model.save(path, keep_previous=True)
    print("saved %s (revision %d)" % (path, model.revision))
    return 0


if __name__ == "__main__":
    sys.exit(main())
