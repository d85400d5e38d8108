#!/usr/bin/env bash
# `make demo`: the whole system in simulation with a scripted audience. The scripted
# scenario and report land with the system issue; until then this starts sim.launch on a
# private master for DEMO_SECONDS and lists what runs.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
set +u
# shellcheck disable=SC1091
. ./env.sh
set -u
if [ -x tools/demo_scenario.py ]; then exec python3 tools/demo_scenario.py "$@"; fi
ROS_HOME="$(mktemp -d /tmp/rbd-demo-home.XXXXXX)"
export ROS_HOME ROS_LOG_DIR="$ROS_HOME/log"
port="$(python3 tools/free_port.py)"
export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_IP=127.0.0.1
roslaunch -p "$port" rbd_bringup sim.launch &
pid=$!
sleep "${DEMO_SECONDS:-10}"
echo "== nodes running:"; rosnode list || true
kill -INT "$pid"; wait "$pid"
