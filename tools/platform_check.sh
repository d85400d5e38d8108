#!/usr/bin/env bash
# Platform check (issue 28): this checkout on another Debian release, in a chroot.
#
#   sudo tools/platform_check.sh bullseye      # Debian 11, the stand-in for Ubuntu 20.04 + Noetic
#   sudo RBD_PLATFORM_BARE=1 tools/platform_check.sh bookworm   # Debian 12 as a bare machine:
#        the README's `make test` alone, timed, in a chroot debootstrapped afresh for the run
#        (no apt, pip, npm or ccache cache; the network as a fresh machine has it)
#
# 1. Debian <release> is debootstrapped once from http://deb.debian.org/debian into
#    $RBD_PLATFORM_CACHE/<release> (default /var/cache/robodog-platform); it is kept between
#    runs with what the runs install (apt packages, the venv, pip/npm caches, ccache).
# 2. The checkout's files (git ls-files: committed, changed and new, not ignored) are copied
#    to /root/robodog in the chroot (its .venv, the ccache and the apt/pip/npm caches stay for the next run; build/ and devel/ do not).
# 3. In the chroot: rbd_local installed with pip into a fresh venv of the chroot's Python and
#    its own tests, then tools/setup.sh (the same script as on Debian 12) and `make test` (build,
#    lint, every gtest/rostest/pytest). RBD_PLATFORM_TESTS=0: setup and build only.
# Prints the versions the README's platform table lists, and ends with `N passed, M failed`
# (make test's count plus rbd_local's); exit 0 only when nothing failed.
# Needs root (debootstrap, chroot, mounts) and the network to Debian, PyPI and npm.
set -euo pipefail
release="${1:-}"
case "$release" in
  bullseye | bookworm) ;;
  *) echo "usage: tools/platform_check.sh bullseye|bookworm   (Debian 11 or 12)" >&2; exit 2 ;;
esac
bare="${RBD_PLATFORM_BARE:-0}"
[ "$(id -u)" -eq 0 ] || { echo "platform_check: needs root (debootstrap, chroot)" >&2; exit 2; }
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${RBD_PLATFORM_CACHE:-/var/cache/robodog-platform}"
chroot_dir="$cache/$release"
t0=$(date +%s)
mkdir -p "$cache"

if [ "$bare" = 1 ] && [ -e "$chroot_dir" ]; then
  echo "platform_check: bare run: removing the cached $chroot_dir first"
  # every mount below it (proc, sys, dev; a network namespace file a failed test left), deepest first
  { findmnt -rn -o TARGET | grep "^$chroot_dir\(/\|$\)" || true; } | sort -r | while read -r m; do umount -l "$m" || true; done
  rm -rf --one-file-system "$chroot_dir"
fi
if [ ! -f "$chroot_dir/.rbd-debootstrap" ]; then
  command -v debootstrap >/dev/null || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap
  echo "platform_check: debootstrap $release into $chroot_dir (once; cached)"
  rm -rf "$chroot_dir.tmp"
  debootstrap --variant=minbase "$release" "$chroot_dir.tmp" http://deb.debian.org/debian > "$cache/debootstrap.log" 2>&1 ||
    { tail -20 "$cache/debootstrap.log"; exit 1; }
  touch "$chroot_dir.tmp/.rbd-debootstrap"
  mv "$chroot_dir.tmp" "$chroot_dir"
fi

mounted=()
cleanup() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do umount -l "${mounted[$i]}" 2>/dev/null || true; done
}
trap cleanup EXIT
# The chroot's / a mount point of its own: `ip netns` (tests/test_two_hosts.py) makes / a slave
# mount, which fails on a plain directory ("mount --make-rslave /": Invalid argument).
if ! mountpoint -q "$chroot_dir"; then
  mount --bind "$chroot_dir" "$chroot_dir"
  mounted+=("$chroot_dir")
fi
for m in proc sys dev dev/pts dev/shm; do
  mkdir -p "$chroot_dir/$m"
  if ! mountpoint -q "$chroot_dir/$m"; then
    mount --bind "/$m" "$chroot_dir/$m"
    mounted+=("$chroot_dir/$m")
  fi
done
cp /etc/resolv.conf "$chroot_dir/etc/resolv.conf"
cp /etc/hosts "$chroot_dir/etc/hosts"
printf 'APT::Install-Recommends "false";\n' > "$chroot_dir/etc/apt/apt.conf.d/90rbd-norecommends"
# minbase has no make, git or ca-certificates (pip and npm need the last); tools/setup.sh does the rest
if [ ! -f "$chroot_dir/.rbd-base-tools" ]; then
  chroot "$chroot_dir" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive \
    sh -c 'apt-get update -qq && apt-get install -y -qq ca-certificates git make procps >/dev/null'
  touch "$chroot_dir/.rbd-base-tools"
fi
# the host's own CAs (a TLS-intercepting proxy) are trusted in the chroot too; pip and npm are
# pointed at the system store (run_in), not at their bundled ones
if ls /usr/local/share/ca-certificates/*.crt > /dev/null 2>&1; then
  mkdir -p "$chroot_dir/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$chroot_dir/usr/local/share/ca-certificates/"
  chroot "$chroot_dir" /usr/sbin/update-ca-certificates > /dev/null
fi

# the checkout, without what is ignored (build products, venv, node_modules)
work="$chroot_dir/root/robodog"
mkdir -p "$work"
# build/ and devel/ too: Debian 11's catkin re-configuring a build it configured before keeps
# GMOCK_FOUND/GMOCK_LIBRARIES (gmock_main;gmock) cached but no longer defines those targets, and
# the gtests stop linking ("No rule to make target 'gmock_main'", 2026-11-29). A fresh build, as
# a fresh clone has; ccache in the chroot keeps it short.
rm -rf "${work:?}"/*
(cd "$root" && git ls-files -z -co --exclude-standard | while IFS= read -r -d '' f; do [ -e "$f" ] && printf '%s\0' "$f"; done |
  tar --null -T - -cf -) | tar -C "$work" -xf -
echo "platform_check: copied $(cd "$root" && git describe --always --dirty) into $work ($(( $(date +%s) - t0 )) s so far)"

run_in() {  # run_in CMD: bash -lc CMD in the chroot's checkout, with a clean environment
  chroot "$chroot_dir" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 TERM=dumb CI="${CI:-}" RBD_JOBS="${RBD_JOBS:-2}" CCACHE_DIR=/root/.ccache \
    PIP_CERT=/etc/ssl/certs/ca-certificates.crt NODE_EXTRA_CA_CERTS=/etc/ssl/certs/ca-certificates.crt \
    RBD_TEST_SEED="${RBD_TEST_SEED:-}" bash -c "cd /root/robodog && $1"
}

log="$cache/$release-make-test.log"
rc=0
if [ "$bare" = 1 ]; then
  # The README's test command on a machine that has nothing yet: setup (apt, venv, npm), build, tests.
  log="$cache/$release-bare-make-test.log"
  echo "platform_check: bare make test in the chroot (log: $log)"
  t1=$(date +%s)
  run_in "make test" > "$log" 2>&1 || rc=$?
  t2=$(date +%s)
  tail -n 30 "$log"
  echo "platform_check: $release bare make test exit $rc in $(( t2 - t1 )) s (setup + build + tests, from nothing)"
  exit "$rc"
fi
if [ "${RBD_PLATFORM_TESTS:-1}" = 0 ]; then
  run_in "tools/setup.sh && make build" || rc=$?
  echo "platform_check: make build exit $rc ($(( $(date +%s) - t0 )) s)"
  exit "$rc"
fi
# rbd_local as a laptop installs it: pip into a fresh venv of this Python, then its tests. It
# runs beside setup and build (mostly downloads), never beside make test's timing tests.
echo "platform_check: pip install ./rbd_local[test] on $(run_in 'python3 --version') and its tests, beside setup + build"
local_log="$cache/$release-rbd_local.log"
local_rc=0
run_in "rm -rf /root/rbd_local_venv && python3 -m venv /root/rbd_local_venv &&
  /root/rbd_local_venv/bin/pip install -q --disable-pip-version-check 'pip==24.3.1' &&
  /root/rbd_local_venv/bin/pip install -q --disable-pip-version-check './rbd_local[test]' &&
  cd rbd_local && xvfb-run -a /root/rbd_local_venv/bin/python -m pytest -q -c ../pytest.ini --rootdir . -p no:randomly tests" \
  > "$local_log" 2>&1 &
local_pid=$!
build_rc=0
run_in "tools/setup.sh && make build" > "$log" 2>&1 || build_rc=$?
echo "platform_check: setup + make build exit $build_rc ($(( $(date +%s) - t0 )) s so far)"
wait "$local_pid" || local_rc=$?
tail -n 5 "$local_log"
local_line="$(grep -E '[0-9]+ (passed|failed)' "$local_log" | tail -1 || true)"
echo "platform_check: rbd_local done ($(( $(date +%s) - t0 )) s so far)"

echo "platform_check: make test in the chroot (log: $log)"
run_in "make test" >> "$log" 2>&1 || rc=$?
tail -n 25 "$log"
main_line="$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$log" | tail -1 || true)"

echo "platform_check: versions in the chroot ($release)"
run_in 'echo "  Debian $(cat /etc/debian_version); $(python3 --version); gcc $(gcc -dumpversion)";
  for p in python3-rospy libpcl-dev python3-numpy liblcm-dev python3-wsproto python3-cbor2 googletest; do
    printf "  %s %s\n" "$p" "$(dpkg-query -W -f="\${Version}" "$p" 2>/dev/null || echo -)"; done' || true

count() {  # count LINE WORD: the number before WORD in a pytest/make-test summary line (0 if none)
  echo "$1" | grep -Eo "[0-9]+ $2" | head -1 | grep -Eo '[0-9]+' || echo 0
}
passed=$(( $(count "$main_line" passed) + $(count "$local_line" passed) ))
failed=$(( $(count "$main_line" failed) + $(count "$local_line" failed) ))
[ -n "$main_line" ] || { echo "platform_check: make test printed no summary (exit $rc): see $log"; failed=$((failed + 1)); }
[ -n "$local_line" ] || { echo "platform_check: rbd_local printed no summary (exit $local_rc): see $local_log"; failed=$((failed + 1)); }
[ "$rc" -eq 0 ] || [ "$failed" -gt 0 ] || failed=1  # a failure without a count still fails
echo "platform_check: $release wall time $(( $(date +%s) - t0 )) s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
