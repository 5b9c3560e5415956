#!/usr/bin/env bash
# The wheel on a new user's machine: a minimal Debian bookworm root (debootstrap --variant=minbase with python3
# and python3-venv only: no OpenSubdiv, no OpenMesh, no compiler), entered with chroot; fresh venvs there install
# the wheel and numpy from PyPI and run `sorpia demo` and a short pytest selection on the installed package
# (tools/clean_root_inside.sh, run inside the root, says what).
#
#   tools/clean_root_test.sh WHEEL      (as root; `make wheel-test` runs it on dist/'s wheel)
#
# The root is made once per machine and kept outside the clone, in $SORPIA_ROOT_CACHE (default
# /var/cache/sorpia): built into a temporary folder and renamed into place only when debootstrap has finished,
# so an interrupted build leaves nothing that a later run trusts. PyPI's files are kept inside the root
# (/var/cache/sorpia-wheels), so later runs fetch nothing they have. /proc and /dev are mounted into the root for
# the run and unmounted on every way out (the EXIT trap, after stopping the run inside); a lock serialises runs.
set -euo pipefail

die() { echo "clean-root test: $*" >&2; exit 1; }
trap 'echo "clean-root test: failed (exit $?) at line $LINENO: $BASH_COMMAND" >&2' ERR

[ $# -eq 1 ] || die "usage: $0 WHEEL"
wheel=$(realpath -e "$1" 2>/dev/null) || die "no wheel at $1 (make wheel writes it)"
case "$wheel" in *.whl) ;; *) die "$1 is not a wheel (.whl)" ;; esac
repo=$(cd "$(dirname "$0")/.." && pwd)
cache=${SORPIA_ROOT_CACHE:-/var/cache/sorpia}
root=$cache/bookworm-root
marker=.sorpia-clean-root  # written last into a finished root, before the rename

[ "$(id -u)" = 0 ] \
  || die "needs root (debootstrap, mount and chroot); without root, install the wheel with: pip install $wheel"
if ! command -v debootstrap >/dev/null; then
  echo "clean-root test: installing debootstrap"
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null; } \
    || die "debootstrap is not installed and 'apt-get install debootstrap' failed: install it, or skip this test"
  command -v debootstrap >/dev/null || die "debootstrap is not on PATH after installing it (PATH=$PATH)"
fi

# The Debian archive the host's apt uses (the network may reach only that one), else Debian's own.
mirror=${SORPIA_DEBIAN_MIRROR:-$(sed -n -e 's|^URIs:[[:space:]]*\([^[:space:]]*/debian\)/\{0,1\}$|\1|p' \
  -e 's|^deb[[:space:]]\{1,\}\([^[:space:]]*/debian\)/\{0,1\}[[:space:]].*|\1|p' \
  /etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list 2>/dev/null | head -n 1 \
  || true)}
mirror=${mirror:-http://deb.debian.org/debian}

# Unmount whatever is mounted at or below $1, deepest first.
unmount_under() {
  local m
  awk -v d="$1" '$2 == d || index($2, d "/") == 1 { print $2 }' /proc/self/mounts | sort -r | while read -r m; do
    umount "$m" 2>/dev/null || umount -l "$m"
  done
}
# Remove a root (or a half-made one): its mounts first; --one-file-system never crosses into a mount that
# could not be undone (a bind-mounted /dev).
remove_root() {
  unmount_under "$1"
  rm -rf --one-file-system "$1"
}

mkdir -p "$cache"
exec 9>"$cache/lock"
flock -w 1800 9 || die "another run has held $cache/lock for 30 minutes"

building=""
work=""
child=""
cleanup() {
  local rc=$? i
  # The run inside the root is its own process group (setsid): stop all of it before unmounting under it.
  if [ -n "$child" ] && kill -0 "$child" 2>/dev/null; then
    kill -TERM -- "-$child" 2>/dev/null || true
    for i in 1 2 3 4 5 6 7 8 9 10; do kill -0 "$child" 2>/dev/null || break; sleep 1; done
    kill -KILL -- "-$child" 2>/dev/null || true
    wait "$child" 2>/dev/null || true
  fi
  unmount_under "$root"
  [ -n "$work" ] && rm -rf --one-file-system "$work"
  [ -n "$building" ] && remove_root "$building"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM HUP

# A killed run (SIGKILL skips the trap) may have left mounts, work folders or a half-made root.
unmount_under "$root"
for stale in "$cache"/bookworm-root.tmp.*; do [ -e "$stale" ] && remove_root "$stale"; done
if [ ! -f "$root/$marker" ]; then
  [ -e "$root" ] && remove_root "$root"
  building=$(mktemp -d "$cache/bookworm-root.tmp.XXXXXX")
  echo "clean-root test: making the root $root (debootstrap bookworm from $mirror; once per machine, minutes)"
  start=$SECONDS
  if ! debootstrap --variant=minbase --include=python3,python3-venv bookworm "$building" "$mirror" \
      >"$cache/debootstrap.log" 2>&1; then
    tail -n 5 "$cache/debootstrap.log" >&2
    die "debootstrap failed (log: $cache/debootstrap.log)"
  fi
  echo "debootstrap --variant=minbase --include=python3,python3-venv bookworm $mirror, $(date -u +%FT%TZ)" \
    >"$building/$marker"
  unmount_under "$building"
  mv -T "$building" "$root"
  building=""
  echo "clean-root test: root made in $((SECONDS - start)) s"
else
  echo "clean-root test: reusing the root $root ($(cat "$root/$marker"))"
fi
rm -rf --one-file-system "$root"/tmp/sorpia-test.*

# What makes the test honest: nothing in the root that the wheel could lean on.
found=$(find "$root/usr" "$root/etc" -name 'libosd*' -o -name 'libOpenMesh*' -o -name 'libgomp*' | head -n 3)
[ -z "$found" ] || die "the root has libraries the wheel must bring itself: $found"
for compiler in cc gcc g++ c++ clang; do
  [ -z "$(find "$root/usr/bin" "$root/usr/local/bin" -maxdepth 1 -name "$compiler")" ] \
    || die "the root has a compiler ($compiler): it is not a new user's machine"
done

work=$(mktemp -d "$root/tmp/sorpia-test.XXXXXX")
inside=/tmp/$(basename "$work")
mkdir -p "$work/wheel" "$work/tests" "$work/noscipy"
cp "$wheel" "$work/wheel/"
cp "$repo/tools/clean_root_inside.sh" "$work/"
# The pytest settings (strict markers, warnings as errors, importlib mode) from the repository's pyproject.toml;
# pytest finds the file above the tests.
cp "$repo/pyproject.toml" "$work/"
for t in conftest.py cli_support.py test_limit.py test_solvers.py test_surface.py test_fair.py test_io.py \
         test_polygons.py test_cli_fit.py test_typing.py; do
  cp "$repo/tests/$t" "$work/tests/"
done
cp "$repo/tests/test_without_scipy.py" "$work/noscipy/"  # apart from conftest.py, which imports scipy
cp -L /etc/resolv.conf "$root/etc/resolv.conf"
# The host's certificate authorities, which may include a proxy's that Debian's bundle in the root lacks.
host_ca=${PIP_CERT:-/etc/ssl/certs/ca-certificates.crt}
[ -f "$host_ca" ] || die "no certificate bundle at $host_ca (PIP_CERT) for pip inside the root"
cp -L "$host_ca" "$work/ca-certificates.crt"

mount -t proc proc "$root/proc"
mount --bind /dev "$root/dev"
# env -i: none of the host's pip settings (find-links, extra index, constraints on this machine's disk) exist
# in the root; pip there uses PyPI as a new user's would.
setsid chroot "$root" /usr/bin/env -i HOME="$inside/home" TMPDIR="$inside/tmp" LANG=C.UTF-8 \
  PATH=/usr/local/bin:/usr/bin:/bin PIP_CERT="$inside/ca-certificates.crt" PIP_DISABLE_PIP_VERSION_CHECK=1 \
  PIP_ROOT_USER_ACTION=ignore /bin/bash "$inside/clean_root_inside.sh" "$inside" "$(basename "$wheel")" &
# In the background and waited for, so that a signal to this script is handled at once (bash runs traps only
# between foreground commands).
child=$!
wait "$child" || die "the run inside the root failed (exit $?): its output is above"
child=""
echo "clean-root test: passed"
