# shellcheck shell=bash
# Source me after `make build`: venv + catkin devel space. Safe under `set -u`.
_rbd_root="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
_rbd_had_u=0
case $- in *u*) _rbd_had_u=1; set +u ;; esac
# shellcheck disable=SC1091
. "$_rbd_root/.venv/bin/activate"
# shellcheck disable=SC1091
. "$_rbd_root/devel/setup.bash"
export RBD_ROOT="$_rbd_root"
if [ "$_rbd_had_u" = 1 ]; then set -u; fi
unset _rbd_had_u _rbd_root
