#!/usr/bin/env bash
# Idempotent machine + venv setup for RoboDog (Debian 12; Debian 11 too, see README "Platforms").
#   1. apt packages from tools/apt-packages.txt (skipped when all are installed); on Debian 11,
#      whose apt has no catkin-tools and no colcon, those two come from PyPI into the venv
#   2. localhost must resolve (roslaunch needs it)
#   3. .venv from /usr/bin/python3 --system-site-packages with pinned requirements
#      (skipped when requirements.txt and rbd_local/pyproject.toml are unchanged)
#   4. roslibjs from npm (beside 3)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
t_setup=$(date +%s)

mapfile -t pkgs < <(grep -v '^\s*#' tools/apt-packages.txt | grep -v '^\s*$')
# nodejs + npm (roslibjs for the bridge's JavaScript client tests, below) in the same apt run:
# one download queue and one round of dpkg triggers instead of two (npm alone is ~350 packages).
if [ ! -d src/rbd_bridge/test/js/node_modules ] && ! command -v npm >/dev/null; then pkgs+=(nodejs npm); fi
codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
pypi=()  # what this release's apt lacks, pip-installed into the venv instead
if [ "$codename" = bullseye ]; then
  # Debian 11: no catkin-tools, no colcon (python3-colcon-*) in apt; PyPI has both. Its pip
  # (20.3) cannot install rbd_local editable from pyproject.toml alone: a newer pip first.
  keep=()
  for p in "${pkgs[@]}"; do
    case "$p" in catkin-tools | colcon | python3-colcon-*) ;; *) keep+=("$p") ;; esac
  done
  pkgs=("${keep[@]}")
  pypi=(pip==24.3.1 catkin-tools==0.9.4 colcon-common-extensions==0.3.0)
elif [ "$codename" != bookworm ]; then
  echo "setup: Debian ${codename:-?} is untested (bookworm and bullseye are); trying anyway" >&2
fi
missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  echo "setup: Debian packages installed ($(( $(date +%s) - t_setup )) s)"
else
  echo "setup: Debian packages present"
fi

if ! getent hosts localhost >/dev/null; then
  echo "127.0.0.1 localhost" >> /etc/hosts
fi

want="$( (cat requirements.txt rbd_local/pyproject.toml; [ ${#pypi[@]} -eq 0 ] || echo "${pypi[*]}") | sha256sum | cut -d' ' -f1)"
have="$(cat .venv/.rbd-requirements 2>/dev/null || true)"
# roslibjs (npm `roslib`) for the bridge's JavaScript client tests: fetched beside the venv's pip
# installs (both mostly wait on the network), its output in build/npm-ci.log.
npm_pid=""
mkdir -p build
if [ ! -d src/rbd_bridge/test/js/node_modules ]; then
  if ! command -v npm >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm
  fi
  echo "setup: npm ci (roslibjs for the bridge tests), beside the venv"
  (cd src/rbd_bridge/test/js && npm ci --no-audit --no-fund --loglevel=error) > build/npm-ci.log 2>&1 &
  npm_pid=$!
fi
if [ "$want" != "$have" ] || [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  [ -x .venv/bin/python ] || /usr/bin/python3 -m venv --system-site-packages .venv
  # catkin and colcon crawl the source space: keep the venv out of it.
  touch .venv/CATKIN_IGNORE .venv/COLCON_IGNORE
  if [ ${#pypi[@]} -gt 0 ]; then
    .venv/bin/python -m pip install -q --disable-pip-version-check "${pypi[@]}"
  fi
  .venv/bin/python -m pip install -q --disable-pip-version-check -r requirements.txt 2>&1 | { grep -v "is ignored: it is neither" || true; }
  .venv/bin/python -m pip install -q --disable-pip-version-check --no-deps -e rbd_local 2>&1 | { grep -v "is ignored: it is neither" || true; }
  echo "$want" > .venv/.rbd-requirements
  echo "setup: .venv done ($(( $(date +%s) - t_setup )) s)"
else
  echo "setup: .venv up to date"
fi

if [ -n "$npm_pid" ]; then
  if ! wait "$npm_pid"; then
    cat build/npm-ci.log >&2
    rm -rf src/rbd_bridge/test/js/node_modules  # a partial install is not "done" for the next run
    echo "setup: npm ci failed (output above)" >&2
    exit 1
  fi
  echo "setup: npm ci done ($(( $(date +%s) - t_setup )) s)"
fi

# Its wall time, for make test's per-phase report (tools/run_tests.sh).
mkdir -p build
printf 'setup: Debian packages, .venv, npm (make setup)\t%s\n' "$(( $(date +%s) - t_setup ))" > build/phase-setup.tsv
