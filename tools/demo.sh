#!/usr/bin/env bash
# `make demo`: the whole system in simulation with a scripted audience (tools/demo_scenario.py).
# VISUAL=1 also opens RViz (audience view) and the operator GUI.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
set +u
# shellcheck disable=SC1091
. ./env.sh
set -u
args=()
if [ "${VISUAL:-0}" = 1 ]; then args+=(--visual); fi
exec python3 tools/demo_scenario.py --out "$root/demo-output" "${args[@]}" "$@"
