"""Only the link package imports roslibpy; gestures/ and gui/ never do (not even indirectly)."""

import ast
import glob
import os
import subprocess
import sys

SRC = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")


def _imports(path):
    tree = ast.parse(open(path).read(), path)
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update("%s.%s" % (node.module, a.name) for a in node.names)
    return names


def test_only_link_imports_roslibpy():
    users = []
    for path in glob.glob(os.path.join(SRC, "rbd_local", "**", "*.py"), recursive=True):
        if any(n == "roslibpy" or n.startswith("roslibpy.") for n in _imports(path)):
            users.append(os.path.relpath(path, SRC))
    assert users and all(u.startswith("rbd_local/link/") for u in users), users


def test_gestures_and_gui_do_not_pull_in_roslibpy_or_link():
    for sub in ("gestures", "gui"):
        for path in glob.glob(os.path.join(SRC, "rbd_local", sub, "*.py")):
            bad = [n for n in _imports(path) if "link" in n.split(".") or n.startswith("roslibpy")]
            assert not bad, (path, bad)
    code = (
        "import sys, pkgutil, importlib, rbd_local.gestures, rbd_local.gui\n"
        "for pkg in (rbd_local.gestures, rbd_local.gui):\n"
        "    for m in pkgutil.iter_modules(pkg.__path__):\n"
        "        importlib.import_module(pkg.__name__ + '.' + m.name)\n"
        "assert 'roslibpy' not in sys.modules and 'rbd_local.link' not in sys.modules, sorted(sys.modules)\n"
    )
    env = dict(os.environ, PYTHONPATH=SRC)
    proc = subprocess.run([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=120)
    assert proc.returncode == 0, proc.stdout[-2000:]
