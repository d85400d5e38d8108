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
ROS_MASTER_URI="http://127.0.0.1:$(python3 tools/free_port.py)"
export ROS_MASTER_URI ROS_IP=127.0.0.1 PYTHONDONTWRITEBYTECODE=1

echo "== catkin run_tests (gtest + rostest)"
start=$(date +%s)
catkin_make --source . --build build -j1 run_tests > "$results/catkin_run_tests.log" 2>&1
rc=$?
echo "   catkin run_tests exit $rc in $(( $(date +%s) - start )) s (log: test-results/catkin_run_tests.log)"
if [ $rc -ne 0 ]; then
  tail -n 40 "$results/catkin_run_tests.log"
  echo "catkin run_tests exited $rc" > "$results/BUILD-FAILED"
fi

echo "== pytest (lint, ROS-free cores, system tests)"
start=$(date +%s)
pytest -q --junitxml="$results/pytest.xml" ${RBD_PYTEST_ARGS:-} src tests
echo "   pytest exit $? in $(( $(date +%s) - start )) s"

# The laptop app is its own pip package: test it from its own root.
echo "== pytest rbd_local (laptop app)"
start=$(date +%s)
(cd rbd_local && pytest -q -c ../pytest.ini --rootdir . --junitxml="$results/pytest-rbd_local.xml" ${RBD_PYTEST_ARGS:-} tests)
echo "   pytest rbd_local exit $? in $(( $(date +%s) - start )) s"

python3 tools/test_summary.py "$results" build/test_results
