#!/usr/bin/env bash
# Every benchmark in the tree: each package's executable bench/run (and rbd_local/bench/run).
# Each writes its report under bench-output/<name>/ and prints its figures; ratios are taken
# within one run because this machine is noisy.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
set +u
# shellcheck disable=SC1091
. ./env.sh
set -u
ROS_HOME="$(mktemp -d /tmp/rbd-bench-home.XXXXXX)"
export ROS_HOME ROS_LOG_DIR="$ROS_HOME/log"
ROS_MASTER_URI="http://127.0.0.1:$(python3 -c 'from rbd_testkit import free_port; print(free_port())')"
export ROS_MASTER_URI ROS_IP=127.0.0.1
mkdir -p bench-output
status=0
found=0
for runner in src/*/bench/run rbd_local/bench/run; do
  [ -x "$runner" ] || continue
  found=1
  name="$(basename "$(dirname "$(dirname "$runner")")")"
  mkdir -p "bench-output/$name"
  echo "== bench: $name ($runner)"
  if ! "$runner" "$root/bench-output/$name"; then
    echo "bench $name FAILED"
    status=1
  fi
done
[ $found = 1 ] || echo "no benchmarks yet"
exit $status
