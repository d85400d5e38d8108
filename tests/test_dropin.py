"""The drop-in claim: the packages under src/ build in a fresh catkin workspace with
catkin_make, catkin build (catkin_tools) and colcon, and every rbd package is found.

The workspace is built the way the robot does it (system python, no venv, nothing of this
checkout's devel space on the paths). Tests are not compiled there (CATKIN_ENABLE_TESTING=OFF)
and C++ is built unoptimised:
`make test` compiles and runs them once in the main build.

`make test` builds with catkin_make (the README's first command); catkin build and colcon are
marked ``long``: `make test-long` (run by `.ci/run` after `make test`) builds with them. Reason:
they were 240 s of the side lane's 840 s (CI, 2026-11-28) and proved nothing about this
repository's code that catkin_make does not, only that the other two tools find and order the
same packages. The repository root as a source space (README: clone the repository into
``catkin_ws/src``) is what `make build` itself does on every `make test`; its result is checked
here from the build's own package order.

catkin_make's workspace is built with `make build`'s flags into build/src, so that every package's
build directory lies where `make build` has it (build/src/<pkg>): with ccache (CCACHE_BASEDIR = the
workspace) its compile lines equal those of `make build` and every object is a cache hit. catkin
build and colcon (long) share their own -O0 flags and layout (src/<pkg>, build/<pkg>): most of the C++
compiled by the first of the two is a cache hit for the other (not the files that include generated
message headers: their include path differs per tool).
"""

import os
import re
import shutil
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = sorted(
    d for d in os.listdir(os.path.join(ROOT, "src")) if os.path.isfile(os.path.join(ROOT, "src", d, "package.xml"))
)
# -O0 for catkin build and colcon (make test-long): they prove the packages build and are found;
# optimised code is built by `make build`. Build type "None" (not empty): rbd_lidar's CMakeLists
# turns an empty build type into Release, whose -O3 came after -O0 on its command lines.
CMAKE_ARGS = ["-DPYTHON_EXECUTABLE=/usr/bin/python3", "-DCATKIN_ENABLE_TESTING=OFF", "-DCMAKE_BUILD_TYPE=None",
              "-DCMAKE_CXX_FLAGS=-O0"]
# catkin_make (make test) with the flags of `make build` (tools/build.sh: Release, warnings as errors):
# with ccache, every object it compiles is the one `make build` compiled minutes before, a cache hit
# (test_catkin_make). On a bare machine the cold -O0 build it did before was 359 s of the side lane
# (~275 CPU-seconds of compiling beside the serial lane's simulations).
CATKIN_MAKE_ARGS = ["-DPYTHON_EXECUTABLE=/usr/bin/python3", "-DCATKIN_ENABLE_TESTING=OFF",
                    "-DCMAKE_BUILD_TYPE=Release", "-DCMAKE_COMPILE_WARNING_AS_ERROR=ON"]
# With a cold cache (a bare machine, or after a C++ change) one tool compiles all the C++: about
# 275 CPU-seconds of compiling (2026-11-26), and catkin_make from cold took over pytest.ini's 600 s at
# load 20 (issue 19).
COLD_BUILD_TIMEOUT = pytest.mark.timeout(1800)
if shutil.which("ccache"):
    # Rebuilds of unchanged sources come from the cache: CCACHE_BASEDIR (set per workspace in run())
    # makes the paths relative, so a fresh workspace at another tmp path still hits.
    CMAKE_ARGS += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]
    CATKIN_MAKE_ARGS += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]


def clean_env():
    """An environment with no ROS workspace sourced (as on a fresh robot shell)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CMAKE_", "PKG_CONFIG", "COLCON"))}
    for key in ("PYTHONPATH", "LD_LIBRARY_PATH", "VIRTUAL_ENV"):
        env.pop(key, None)
    env["PATH"] = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
    if shutil.which("ccache"):
        env["CCACHE_BASEDIR"] = "/tmp"
    return env


def run(cmd, cwd):
    env = clean_env()
    env["PWD"] = cwd  # catkin_make takes its base path from PWD
    env["CCACHE_BASEDIR"] = cwd
    proc = subprocess.run(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True)
    assert proc.returncode == 0, "%s failed:\n%s" % (" ".join(cmd), proc.stdout[-6000:])
    return proc.stdout


@pytest.fixture
def workspace(tmp_path):
    """A fresh catkin workspace with this repository's packages copied under src/."""
    src = tmp_path / "ws" / "src"
    src.mkdir(parents=True)
    for pkg in PACKAGES:
        shutil.copytree(os.path.join(ROOT, "src", pkg), str(src / pkg),
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return tmp_path / "ws"


def test_every_rbd_package_is_a_package():
    expected = {"robodog", "rbd_msgs", "rbd_lidar", "rbd_controller", "rbd_pos_controller", "rbd_localization",
                "rbd_navigation", "rbd_gestrec", "rbd_bridge", "rbd_a1_driver", "rbd_sim", "rbd_bringup",
                "rbd_description", "rbd_preflight",
                "rbd_wire_oracle", "rbd_testkit", "rbd_geometry"}
    assert set(PACKAGES) == expected


@COLD_BUILD_TIMEOUT
def test_catkin_make(workspace):
    # Build space build/src: each package's build directory is then build/src/<pkg>, as in `make build`
    # (source space = the repository root, packages in src/), so with CCACHE_BASEDIR the compile lines,
    # relative to the build directory, are the same and hit the cache. Nothing else differs for catkin_make.
    out = run(["catkin_make", "-j2", "--build", "build/src"] + CATKIN_MAKE_ARGS, str(workspace))
    for pkg in PACKAGES:
        assert "+++ processing catkin" in out and ("'%s'" % pkg) in out, pkg
    assert (workspace / "devel" / "share" / "rbd_msgs" / "msg").exists() or (
        workspace / "devel" / "lib" / "python3" / "dist-packages" / "rbd_msgs" / "srv" / "__init__.py"
    ).exists()


@pytest.mark.long
@COLD_BUILD_TIMEOUT
def test_catkin_build(workspace):
    run(["catkin", "init"], str(workspace))
    run(["catkin", "config", "--cmake-args"] + CMAKE_ARGS, str(workspace))
    listed = run(["catkin", "list", "-u"], str(workspace)).split()
    assert set(PACKAGES) <= set(listed)
    run(["catkin", "build", "-j2", "--no-status", "--no-notify"], str(workspace))
    for pkg in PACKAGES:
        assert (workspace / "devel" / ".private" / pkg).is_dir(), pkg


@pytest.mark.long
@COLD_BUILD_TIMEOUT
def test_colcon_build(workspace):
    listed = run(["colcon", "list", "--names-only"], str(workspace)).split()
    assert set(PACKAGES) == set(listed)
    run(["colcon", "build", "--parallel-workers", "2", "--event-handlers", "console_direct-"] +
        ["--cmake-args"] + CMAKE_ARGS, str(workspace))
    for pkg in PACKAGES:
        assert (workspace / "install" / pkg / "share" / pkg / "package.xml").exists(), pkg


def test_make_build_used_the_repository_root_and_found_every_package():
    """`make build` is `catkin_make --source <repo>`: its package order lists every package."""
    order = os.path.join(ROOT, "build", "catkin_generated", "order_packages.cmake")
    assert os.path.isfile(order), "no %s: run `make build` first" % order
    with open(order) as f:
        text = f.read()
    found = set(re.findall(r'CATKIN_ORDERED_PACKAGES "([^"]+)"', text))
    assert set(PACKAGES) <= found, "make build did not see %s" % sorted(set(PACKAGES) - found)
    # paths are relative to the source space: the repository root, nothing found outside src/
    paths = set(re.findall(r'CATKIN_ORDERED_PACKAGE_PATHS "([^"]+)"', text))
    assert paths == {"src/%s" % p for p in found}, sorted(paths)
