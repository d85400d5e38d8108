#!/usr/bin/env bash
# `make test-long`: the tests marked `long` (pytest marker; README "Tests" gives each one's reason),
# run after `make test` by .ci/run. Ends with one line `N passed, M failed`; non-zero exit on any
# failure or when no test ran. Results in test-results-long/ (make test's own stay untouched).
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
set +u
# shellcheck disable=SC1091
. ./env.sh
set -u
results="$root/test-results-long"
rm -rf "$results"
mkdir -p "$results"
ROS_HOME="$(mktemp -d /tmp/rbd-test-long-home.XXXXXX)"
export ROS_HOME ROS_LOG_DIR="$ROS_HOME/log" PYTHONDONTWRITEBYTECODE=1 RBD_TEST_LONG=1
start=$(date +%s)
echo "== make test-long: the tests marked long (log: test-results-long/pytest.log)"
pytest -q -m long --durations=10 --junitxml="$results/pytest.xml" ${RBD_PYTEST_ARGS:-} src tests \
  > "$results/pytest.log" 2>&1
echo "   pytest -m long exit $? in $(( $(date +%s) - start )) s"
grep -E "^(FAILED|ERROR) |passed|failed" "$results/pytest.log" | tail -n 20
printf 'long: pytest -m long\t%s\n' "$(( $(date +%s) - start ))" > "$results/phases.tsv"
rm -rf "$ROS_HOME"
python3 tools/test_summary.py --phases "$results/phases.tsv" --slowest 5 "$results"
