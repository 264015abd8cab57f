#!/usr/bin/env bash
# deb_install.sh SRC BUILD: the Debian package installs into a fresh root of the release it was
# built on (bookworm: Wireshark 4.0, trixie: 4.4, sid: 4.6) with `apt-get install ./ncservo_*.deb`;
# then `tshark -G plugins` lists ncservo for a non-root user and `ncservo --version` works. The root
# comes from .ci/debian-root.sh, from its cached base of the release; without one it is made with
# debootstrap only under CI (CI set) — it takes minutes — and the test is skipped (77, saying why)
# otherwise.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (chroot, apt-get in it)"
if grep -q '^NCSERVO_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  echo "SKIPPED: a sanitizer build's package is not one to install (the plain build's run tests it)"
  exit 77
fi
release=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
grep -q '/sid' /etc/os-release && release=sid
[ -n "$release" ] || fail "no VERSION_CODENAME in /etc/os-release"
root_tool="$SRC/.ci/debian-root.sh"
if [ -z "${CI:-}" ] && ! "$root_tool" has-base "$release"; then
  echo "SKIPPED: no cached $release root; make one with '$root_tool base $release'," \
    "or run under CI (CI=1) to make it here"
  exit 77
fi
(cd "$BUILD" && rm -f ncservo_*.deb && cpack -G DEB >"$WORK/cpack.log" 2>&1) || fail "cpack: $(tail -5 "$WORK/cpack.log")"
debs=("$BUILD"/ncservo_*_amd64.deb)
[ -f "${debs[0]}" ] || fail "no ncservo_<version>_amd64.deb in $BUILD"
# The libwireshark package of the Wireshark built against (libwireshark16 for 4.0, 18 for 4.4).
libwireshark=$(dpkg -S "$(readlink -f /usr/lib/*/libwireshark.so)" | cut -d: -f1)
dpkg-deb -f "${debs[0]}" Depends | grep -qw "$libwireshark" ||
  fail "Depends lacks $libwireshark: $(dpkg-deb -f "${debs[0]}" Depends)"

root=$WORK/root
trap '"$root_tool" remove "$root" || true; rm -rf "$WORK"' EXIT
"$root_tool" create "$release" "$root" >"$WORK/root.log" 2>&1 || fail "$release root: $(tail -5 "$WORK/root.log")"
cp "${debs[0]}" "$root/tmp/"
in_root() { "$root_tool" run "$root" "$@"; }
in_root apt-get update -qq >"$WORK/apt.log" 2>&1 || fail "apt-get update: $(tail -5 "$WORK/apt.log")"
in_root apt-get install -y -qq --no-install-recommends "/tmp/$(basename "${debs[0]}")" tshark \
  >>"$WORK/apt.log" 2>&1 || fail "apt-get install: $(tail -10 "$WORK/apt.log")"
in_root ncservo --version | grep -q "^ncservo " || fail "ncservo --version"
in_root setpriv --reuid=65534 --regid=65534 --clear-groups env HOME=/tmp tshark -G plugins \
  >"$WORK/plugins" 2>&1 || fail "tshark -G plugins: $(head -5 "$WORK/plugins")"
grep -q "ncservo.so" "$WORK/plugins" || fail "tshark -G plugins does not list ncservo: $(cat "$WORK/plugins")"
[ -f "$root/usr/share/man/man1/ncservo.1" ] || fail "no man page"
echo "PASS: $(basename "${debs[0]}") (Depends $libwireshark) installed in $release, tshark lists $(grep ncservo.so "$WORK/plugins" | cut -f1-2)"
