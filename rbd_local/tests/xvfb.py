"""A private Xvfb on a free display (Xvfb picks it via -displayfd), and pumping a Tk window."""

import os
import subprocess
import time


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


def pump(root, until, timeout=5.0):
    """Run the Tk event loop of ``root`` until ``until()`` is true or ``timeout`` passed; return it."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        root.update()
        if until():
            return True
        time.sleep(0.02)
    root.update()
    return until()
