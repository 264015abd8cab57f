#!/usr/bin/env bash
# deb_install.sh SRC BUILD: the Debian package installs into a fresh Debian bookworm
# root with `apt-get install ./ncservo_*.deb`; then `tshark -G plugins` lists ncservo for a
# non-root user and `ncservo --version` works. The root is a copy of a cached minimal bookworm
# (NCSERVO_BOOKWORM_ROOT, default BUILD/bookworm-root); without one it is made with debootstrap
# only under CI (CI set) — it takes minutes — and the test is skipped (77, saying why) otherwise.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (chroot, apt-get in it)"
if grep -q '^NCSERVO_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  echo "SKIPPED: a sanitizer build's package is not one to install (the plain build's run tests it)"
  exit 77
fi
cached=${NCSERVO_BOOKWORM_ROOT:-$BUILD/bookworm-root}
if [ ! -x "$cached/usr/bin/apt-get" ]; then
  if [ -z "${CI:-}" ]; then
    echo "SKIPPED: no cached bookworm root at $cached; make one with" \
      "'debootstrap --variant=minbase bookworm $cached', or run under CI (CI=1) to make it here"
    exit 77
  fi
  require_program debootstrap
  debootstrap --variant=minbase bookworm "$cached.partial" "${NCSERVO_DEBIAN_MIRROR:-http://deb.debian.org/debian}" >"$WORK/debootstrap.log" 2>&1 ||
    fail "debootstrap: $(tail -5 "$WORK/debootstrap.log")"
  mv "$cached.partial" "$cached"
fi

(cd "$BUILD" && rm -f ncservo_*.deb && cpack -G DEB >"$WORK/cpack.log" 2>&1) || fail "cpack: $(tail -5 "$WORK/cpack.log")"
debs=("$BUILD"/ncservo_*_amd64.deb)
[ -f "${debs[0]}" ] || fail "no ncservo_<version>_amd64.deb in $BUILD"
dpkg-deb -f "${debs[0]}" Depends | grep -q libwireshark || fail "Depends lacks libwireshark: $(dpkg-deb -f "${debs[0]}" Depends)"

root=$WORK/root
cp -a "$cached" "$root"
cp /etc/resolv.conf "$root/etc/resolv.conf"
cp "${debs[0]}" "$root/tmp/"
mount -t proc proc "$root/proc"
trap 'umount "$root/proc" 2>/dev/null; rm -rf "$WORK"' EXIT
in_root() { chroot "$root" env DEBIAN_FRONTEND=noninteractive PATH=/usr/sbin:/usr/bin:/sbin:/bin "$@"; }
in_root apt-get update -qq >"$WORK/apt.log" 2>&1 || fail "apt-get update: $(tail -5 "$WORK/apt.log")"
in_root apt-get install -y -qq --no-install-recommends "/tmp/$(basename "${debs[0]}")" tshark \
  >>"$WORK/apt.log" 2>&1 || fail "apt-get install: $(tail -10 "$WORK/apt.log")"
in_root ncservo --version | grep -q "^ncservo " || fail "ncservo --version"
in_root setpriv --reuid=65534 --regid=65534 --clear-groups env HOME=/tmp tshark -G plugins \
  >"$WORK/plugins" 2>&1 || fail "tshark -G plugins: $(head -5 "$WORK/plugins")"
grep -q "ncservo.so" "$WORK/plugins" || fail "tshark -G plugins does not list ncservo: $(cat "$WORK/plugins")"
[ -f "$root/usr/share/man/man1/ncservo.1" ] || fail "no man page"
echo "PASS: $(basename "${debs[0]}") installed, tshark lists $(grep ncservo.so "$WORK/plugins" | cut -f1-2)"
