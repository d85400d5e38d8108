#!/usr/bin/env bash
# Every test in the tree: lint, gtest + rostest (catkin run_tests), pytest (ROS-free cores,
# rbd_local, tests/). Ends with one line `N passed, M failed`; non-zero exit on any failure
# or when no test ran. Tests get their own ROS_HOME and a master port that is free.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
set +u
# shellcheck disable=SC1091
. ./env.sh
set -u
results="$root/test-results"
rm -rf "$results" build/test_results
mkdir -p "$results"
ROS_HOME="$(mktemp -d /tmp/rbd-test-home.XXXXXX)"
export ROS_HOME ROS_LOG_DIR="$ROS_HOME/log"
ROS_MASTER_URI="http://127.0.0.1:$(python3 -c 'from rbd_testkit import free_port; print(free_port())')"
export ROS_MASTER_URI ROS_IP=127.0.0.1 PYTHONDONTWRITEBYTECODE=1
# One test-order seed per run: pytest (pytest-randomly) and rostest node scripts (rbd_testkit's
# run_rostest) shuffle with it. RBD_TEST_SEED=N make test repeats an order.
RBD_TEST_SEED="${RBD_TEST_SEED:-$(( (RANDOM << 15 | RANDOM) + 1 ))}"
export RBD_TEST_SEED
echo "== test order seed $RBD_TEST_SEED (RBD_TEST_SEED=$RBD_TEST_SEED make test repeats it)"
phases="$results/phases.tsv"
: > "$phases"
t_all=$(date +%s)

echo "== catkin run_tests (gtest + rostest)"
start=$(date +%s)
catkin_make --source . --build build -j1 run_tests > "$results/catkin_run_tests.log" 2>&1
rc=$?
echo "   catkin run_tests exit $rc in $(( $(date +%s) - start )) s (log: test-results/catkin_run_tests.log)"
printf 'catkin run_tests (gtest + rostest)\t%s\n' "$(( $(date +%s) - start ))" >> "$phases"
if [ $rc -ne 0 ]; then
  tail -n 40 "$results/catkin_run_tests.log"
  echo "catkin run_tests exited $rc" > "$results/BUILD-FAILED"
fi

echo "== pytest (lint, ROS-free cores, system tests)"
start=$(date +%s)
pytest -q -p randomly --randomly-seed="$RBD_TEST_SEED" --durations=15 --junitxml="$results/pytest.xml" \
  ${RBD_PYTEST_ARGS:-} src tests
echo "   pytest exit $? in $(( $(date +%s) - start )) s"
printf 'pytest src tests\t%s\n' "$(( $(date +%s) - start ))" >> "$phases"

# The laptop app is its own pip package: test it from its own root.
echo "== pytest rbd_local (laptop app)"
start=$(date +%s)
(cd rbd_local && pytest -q -c ../pytest.ini --rootdir . -p randomly --randomly-seed="$RBD_TEST_SEED" \
  --durations=15 --junitxml="$results/pytest-rbd_local.xml" ${RBD_PYTEST_ARGS:-} tests)
echo "   pytest rbd_local exit $? in $(( $(date +%s) - start )) s"
printf 'pytest rbd_local\t%s\n' "$(( $(date +%s) - start ))" >> "$phases"
printf 'total\t%s\n' "$(( $(date +%s) - t_all ))" >> "$phases"

# The closing `N passed, M failed` line, then the wall time per phase, the 15 slowest tests
# (pytest and rostest, from the JUnit files) and the seed.
python3 tools/test_summary.py --phases "$phases" --slowest 15 --seed "$RBD_TEST_SEED" "$results" build/test_results
