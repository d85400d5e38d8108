"""One way for the system tests to run ``run_all`` and read its results.

Used by test_experiments.py (the thesis experiments in make test) and
test_avoidance_experiments.py (issue 17's box and wall, behind RBD_AVOIDANCE_EXPERIMENTS).
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def run_all(args, timeout, keep=None):
    """Run ``run_all ARGS --out DIR`` and yield its results.json (for a module fixture: ``yield from``).

    Args:
        args: run_all's arguments without ``--out``.
        timeout: seconds it may run; then SIGINT reaches run_all and its experiment processes
            (their own process group), which stop their simulator stacks on the way out.
        keep: an output directory to keep; None: a temporary one, removed afterwards.

    Yields:
        The results.json content with ``stdout`` (run_all's output) and ``out`` (the directory).
    """
    out = keep or tempfile.mkdtemp(prefix="rbd-experiments.")
    proc = subprocess.Popen([sys.executable, os.path.join(HERE, "run_all")] + list(args) + ["--out", out],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                            start_new_session=True)
    try:
        stdout, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGINT)
        stdout, _ = proc.communicate(timeout=60)
    try:
        path = os.path.join(out, "results.json")
        if not os.path.exists(path):
            raise AssertionError("run_all %s wrote no results.json (exit %s); its output:\n%s"
                                 % (" ".join(args), proc.returncode, stdout[-6000:]))
        with open(path) as fh:
            data = json.load(fh)
        data["stdout"] = stdout
        data["out"] = out
        yield data
    finally:
        if not keep:
            shutil.rmtree(out, ignore_errors=True)


def result(run, name):
    """One experiment's result; fails the test with run_all's output when it raised."""
    r = run["results"][name]
    assert "error" not in r, "%s: %s\n%s" % (name, r.get("error"), run["stdout"][-3000:])
    return r
