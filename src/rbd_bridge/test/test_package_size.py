"""Issue 18's size targets hold: the package at most 3,200 lines, no file over 500 (``wc -l``)."""

import pathlib

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / "src" / "rbd_bridge"


def _lines():
    return {str(p.relative_to(PACKAGE)): len(p.read_bytes().splitlines()) for p in sorted(PACKAGE.rglob("*.py"))}


def test_the_package_is_at_most_3200_lines_and_no_file_over_500():
    lines = _lines()
    assert len(lines) >= 19 and "core/session.py" in lines  # the tree it means, not an empty glob
    assert sum(lines.values()) <= 3200, "%d lines: %s" % (sum(lines.values()), lines)
    assert max(lines.values()) <= 500, {name: n for name, n in lines.items() if n > 500}
