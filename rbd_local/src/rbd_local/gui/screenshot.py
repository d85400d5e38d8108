"""Save a Tk window as PNG with ImageMagick's ``import`` (X11, works under Xvfb)."""

import subprocess


def save_window(root: object, path: str) -> None:
    """Grab the window of ``root`` into ``path``.

    Raises:
        RuntimeError: if ``import`` fails.
    """
    root.update()
    window_id = root.winfo_id()
    # The toplevel frame is the parent of the Tk frame id on X11.
    wrapper = root.wm_frame()
    target = wrapper if wrapper and wrapper != "0x0" else str(window_id)
    proc = subprocess.run(["import", "-window", str(target), path], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=30)
    if proc.returncode != 0:
        raise RuntimeError("import failed: %s" % proc.stdout)
