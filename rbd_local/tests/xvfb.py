"""A private Xvfb on a free display (Xvfb picks it via -displayfd), and pumping a Tk window."""

import os
import subprocess
import time

from rbd_testkit import wait_for


class Xvfb:
    def __init__(self, size="1024x768x24"):
        self.size = size
        self.proc = None
        self.display = None

    def start(self):
        r, w = os.pipe()
        self.proc = subprocess.Popen(
            ["Xvfb", "-displayfd", str(w), "-screen", "0", self.size, "-nolisten", "tcp"],
            pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
        os.close(w)
        deadline = time.monotonic() + 20
        buf = b""
        with os.fdopen(r, "rb") as fh:
            while not buf.endswith(b"\n") and time.monotonic() < deadline:
                chunk = fh.read(1)
                if not chunk:
                    break
                buf += chunk
        if not buf.strip():
            self.stop()
            raise RuntimeError("Xvfb did not report a display")
        self.display = ":" + buf.decode().strip()
        return self

    def stop(self):
        if self.proc is not None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
            self.proc = None


#: How long a window may take to show what it must (liveness, not a speed claim: make test runs
#: these tests niced beside simulated stacks, and a starved test process has stalled for seconds).
LIVENESS_S = 60.0


def pump_for(root, seconds):
    """Run the Tk event loop of ``root`` for ``seconds``."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        root.update()
        time.sleep(0.02)
    root.update()


def pump(root, until, timeout=LIVENESS_S):
    """Run the Tk event loop of ``root`` until ``until()`` is true or ``timeout`` passed; return it.

    When it is still false at the end, the threads' stacks and how fast roslibpy's reactor answers
    go to stderr (the failed test's captured output): why a window waited in vain, not only that.
    """
    def pumped():
        root.update()
        return until()

    if wait_for(pumped, timeout, 0.02):
        return True
    print_threads()
    return False


def print_threads():
    """Every thread's stack, and the reactor's reply time if Twisted's reactor runs, to stderr."""
    import sys
    import threading
    import traceback

    frames = sys._current_frames()
    for thread in threading.enumerate():
        frame = frames.get(thread.ident)
        print("--- thread %s (daemon %s)" % (thread.name, thread.daemon), file=sys.stderr)
        if frame is not None:
            traceback.print_stack(frame, limit=8, file=sys.stderr)
    if "twisted.internet.reactor" in sys.modules:
        from twisted.internet import reactor

        if reactor.running:
            answered = threading.Event()
            t0 = time.monotonic()
            reactor.callFromThread(answered.set)
            ok = answered.wait(10.0)
            print("--- reactor answered %s after %.2f s" % ("" if ok else "NOT", time.monotonic() - t0),
                  file=sys.stderr)
