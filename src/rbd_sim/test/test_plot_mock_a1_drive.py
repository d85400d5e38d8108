"""The scripted-drive plot: writes a PNG and reports the drift of the open-loop loop."""

import os
import re
import subprocess
import sys

SCRIPT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "plot_mock_a1_drive")


def test_plot_offline(tmp_path):
    out = tmp_path / "drive.png"
    proc = subprocess.run([sys.executable, SCRIPT, str(out)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=120)
    assert proc.returncode == 0, proc.stdout
    with open(str(out), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    ends = [float(x) for x in re.findall(r"end ([0-9.]+) m from start", proc.stdout)]
    assert len(ends) == 2
    # Turn out and back: 2 x 0.4 m sideways with the drift on; back home with it off.
    assert 0.7 < ends[0] < 0.95 and ends[1] < 0.05
