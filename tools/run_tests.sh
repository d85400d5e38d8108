#!/usr/bin/env bash
# Every test in the tree: lint, gtest + rostest (catkin's run_tests targets), pytest (ROS-free
# cores, rbd_local, tests/). Ends with one line `N passed, M failed`; non-zero exit on any failure
# or when no test ran. Tests get their own ROS_HOME and a master port that is free.
#
# Two lanes run side by side (2 cores; most of a rostest is waiting):
#   serial lane: everything that starts a simulated stack (sim.launch, mock_a1.launch,
#     sensors.launch, a bag replay, the demo, the soak, the experiments, two hosts), one at a
#     time, at normal priority: two timing-sensitive simulated stacks never run at once.
#   side lane: gtests and the rostests that start no simulated stack, then (niced) pytest of
#     the rest (ROS-free cores, private-master node tests, lint, drop-in builds) with rbd_local's
#     pytest beside it.
# RBD_TEST_LANES=1 runs the side lane after the serial lane instead of beside it.
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
# setup and build (written by tools/setup.sh and tools/build.sh in this make run) come first
cat build/phase-setup.tsv build/phase-build.tsv > "$phases" 2>/dev/null || true
rm -f build/phase-setup.tsv build/phase-build.tsv  # a later tools/run_tests.sh alone has none
t_all=$(date +%s)

# pytest files that start a simulated stack: the serial lane runs them after the rostests.
serial_pytest=(tests/test_demo.py tests/test_soak.py tests/test_two_hosts.py tests/experiments
               tests/test_sim_gui.py src/rbd_bringup/test/test_robot_bringup.py src/rbd_bringup/test/test_replay.py)
# A rostest file starts a simulated stack when it includes one of these launch files or plays a bag;
# a file that measures rates or latencies says `make test: serial lane` in a comment. A file that
# matches but only starts sensor stand-ins (no mock A1, driver or controllers: as light as
# people.test) and bounds no latency says `make test: side lane` in a comment, with its reason.
sim_pattern='launch/(sim|mock_a1|sensors)\.launch|pkg="rosbag"|make test: serial lane'
side_marker='make test: side lane'

phase() {  # phase NAME START: append the wall time since START to the phases table
  printf '%s\t%s\n' "$1" "$(( $(date +%s) - $2 ))" >> "$phases"
}

# catkin's run_tests target of each gtest and rostest file, split by lane.
serial_targets=()
side_targets=()
test_file() {  # test_file TARGET: the .test file of a rostest target (empty for a gtest)
  local t=$1 pkg f rel
  for pkg in $(ls src); do
    case "$t" in
      "run_tests_${pkg}_rostest_"*)
        for f in $(find "src/$pkg" -name '*.test'); do
          rel="${f#src/"$pkg"/}"
          [ "run_tests_${pkg}_rostest_${rel//\//_}" = "$t" ] && { echo "$f"; return; }
        done ;;
    esac
  done
}
collect_targets() {
  local t f
  for t in $(make -s -C build help | sed -n 's/^\.\.\. \(run_tests_.*_\(gtest\|rostest\|nosetests\)_[^/]*\)$/\1/p' | sort); do
    f=$(test_file "$t")
    if [ -n "$f" ] && grep -Eq "$sim_pattern" "$f" && ! grep -q "$side_marker" "$f"; then
      serial_targets+=("$t")
    else
      side_targets+=("$t")
    fi
  done
}

run_targets() {  # run_targets LOG TARGET...: catkin's run_tests commands, /fast: nothing rebuilt
  # (catkin's _run_tests_* variants would also clean build/test_results: never use those here)
  local log=$1 t
  shift
  for t in "$@"; do
    echo "-- $t" >> "$log"
    make -s -C build "$t/fast" >> "$log" 2>&1 || echo "   $t exit $?" >> "$log"
  done
}

serial_lane() {
  local start
  echo "== serial lane: ${#serial_targets[@]} rostests with a simulated stack (log: test-results/rostest_serial.log)"
  start=$(date +%s)
  run_targets "$results/rostest_serial.log" "${serial_targets[@]}"
  echo "   serial rostests done in $(( $(date +%s) - start )) s"
  phase "serial: rostests with a simulated stack" "$start"
  echo "== serial lane: pytest system tests (${serial_pytest[*]})"
  start=$(date +%s)
  # one pytest process per file: a test that makes this process a ROS node (rospy.init_node, once
  # per process, on one master) must not meet another file's node. No system test uses hypothesis:
  # without its pytest plugin a process starts in 0.8 s instead of 1.7-3.2 s (load 3-5).
  local f rc=0 n=0
  for f in "${serial_pytest[@]}"; do
    n=$((n + 1))
    pytest -q -p randomly -p no:hypothesispytest --randomly-seed="$RBD_TEST_SEED" --durations=5 \
      --junitxml="$results/pytest-system-$n.xml" ${RBD_PYTEST_ARGS:-} "$f" || rc=$?
  done
  echo "   pytest system tests exit $rc in $(( $(date +%s) - start )) s"
  phase "serial: pytest system tests" "$start"
}

side_lane() {
  local start ignores=() p
  start=$(date +%s)
  # test executables (gtest) first; the nodes themselves were built by `make build` (plain make:
  # no cmake re-run under the serial lane's feet). CCACHE_BASEDIR as in tools/build.sh: the test
  # objects of another clone or worktree of the same sources are cache hits (without it their
  # absolute paths missed, ~150 s of compiling in a fresh clone's side lane)
  if ! CCACHE_BASEDIR="$root" nice -n 10 make -C build -j2 tests > "$results/catkin_tests_build.log" 2>&1; then
    tail -n 40 "$results/catkin_tests_build.log"
    echo "building the test executables failed" > "$results/BUILD-FAILED"
  fi
  run_targets "$results/rostest_side.log" "${side_targets[@]}"
  phase "side: gtests + rostests without a simulated stack" "$start"
  # The laptop app is its own pip package: test it from its own root, beside the pytest of the
  # rest. Both are niced and mostly wait (rosmasters, subprocesses, the serial lane's stacks left
  # the two cores ≈ 40 % idle with one pytest here); its output follows the other's in the log.
  start=$(date +%s)
  (
    cd rbd_local && nice -n 10 pytest -q -c ../pytest.ini --rootdir . -p randomly --randomly-seed="$RBD_TEST_SEED" \
      --durations=15 --junitxml="$results/pytest-rbd_local.xml" ${RBD_PYTEST_ARGS:-} tests
    echo "   pytest rbd_local exit $? in $(( $(date +%s) - start )) s"
    phase "side: pytest rbd_local (beside pytest src tests)" "$start"
  ) > "$results/rbd_local.log" 2>&1 &
  local local_pid=$!
  for p in "${serial_pytest[@]}"; do ignores+=(--ignore="$p"); done
  nice -n 10 pytest -q -p randomly --randomly-seed="$RBD_TEST_SEED" --durations=15 --junitxml="$results/pytest.xml" \
    ${RBD_PYTEST_ARGS:-} "${ignores[@]}" src tests
  echo "   pytest src tests (without the system tests) exit $? in $(( $(date +%s) - start )) s"
  phase "side: pytest src tests (lint, cores, node tests, drop-in)" "$start"
  wait "$local_pid"
  cat "$results/rbd_local.log"
}

collect_targets
if [ $(( ${#serial_targets[@]} + ${#side_targets[@]} )) -eq 0 ]; then
  echo "no run_tests targets in build/ (was it built with CATKIN_ENABLE_TESTING?)" > "$results/BUILD-FAILED"
fi
echo "== side lane: ${#side_targets[@]} gtests/rostests without a simulated stack, then pytest (log: test-results/side_lane.log)"
if [ "${RBD_TEST_LANES:-2}" = 1 ]; then
  serial_lane
  side_lane > "$results/side_lane.log" 2>&1
else
  side_lane > "$results/side_lane.log" 2>&1 &
  side_pid=$!
  serial_lane
  wait "$side_pid"
fi
echo "== side lane output"
grep -E "^(FAILED|ERROR) |passed|failed| exit " "$results/side_lane.log" | tail -n 40
phase "total of the test phases" "$t_all"
# the lanes overlap: the whole is setup + build + the test phases' total
awk -F'\t' '/^(setup|build|total)/ { s += $2 } END { printf "make test: setup + build + tests\t%d\n", s }' \
  "$phases" > "$phases.sum"
cat "$phases.sum" >> "$phases" && rm -f "$phases.sum"

# The closing `N passed, M failed` line, then the wall time per phase, the 15 slowest tests
# (pytest and rostest, from the JUnit files) and the seed.
python3 tools/test_summary.py --phases "$phases" --slowest 15 --seed "$RBD_TEST_SEED" "$results" build/test_results
