#!/usr/bin/env bash
# catkin_make with this repository as the source space, into build/ and devel/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
t_build=$(date +%s)
# Keep build products out of package crawling (catkin_make, catkin build, colcon).
mkdir -p build devel/lib/python3/dist-packages
for d in build devel; do touch "$d/CATKIN_IGNORE" "$d/COLCON_IGNORE"; done
set +u
# shellcheck disable=SC1091
. .venv/bin/activate
set -u
launcher=()
# Paths under the checkout are hashed relative to it, so clones and worktrees share ccache hits.
export CCACHE_BASEDIR="$root"
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
# CI builds treat warnings as errors (a plain drop-in build does not: see the C++ CMakeLists).
catkin_make --source . --build build -j"${RBD_JOBS:-2}" \
  -DPYTHON_EXECUTABLE="$root/.venv/bin/python3" -DCMAKE_BUILD_TYPE=Release -DCMAKE_COMPILE_WARNING_AS_ERROR=ON "${launcher[@]}" "$@"
# Its wall time, for make test's per-phase report (tools/run_tests.sh).
printf 'build: catkin_make (make build)\t%s\n' "$(( $(date +%s) - t_build ))" > build/phase-build.tsv
