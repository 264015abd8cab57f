#!/usr/bin/env bash
# debian_root_mirror.sh SRC BUILD: .ci/debian-root.sh takes the Debian archive from the machine's
# own apt sources, never from an address written in the repository: the first deb source that is
# not the security archive, from the deb822 files (sources.list.d/*.sources) or else from
# sources.list (its [options] skipped), one line exactly; none at all is an error that says where
# it looked; NCSERVO_DEBIAN_MIRROR still names another.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
mirror() { NCSERVO_APT_ETC="$WORK/apt" "$SRC/.ci/debian-root.sh" mirror; }
expect_mirror() {  # expect_mirror WANT WHAT
  local got
  got=$(mirror) || fail "$2: exit $?"
  [ "$got" = "$1" ] || fail "$2: '$got', expected '$1'"
  echo "ok $2: $got"
}
mkdir -p "$WORK/apt/sources.list.d"
cat >"$WORK/apt/sources.list.d/debian.sources" <<'SRC822'
Types: deb
URIs: http://security.example/debian-security
Suites: bookworm-security
Components: main

Types: deb-src
URIs: http://source-only.example/debian
Suites: bookworm

Types: deb
URIs: http://archive.example/debian/ http://second.example/debian
Suites: bookworm bookworm-updates
Components: main

Types: deb
URIs: http://later.example/debian
Suites: bookworm-backports
Components: main
SRC822
printf 'deb http://list.example/debian bookworm main\n' >"$WORK/apt/sources.list"
expect_mirror http://archive.example/debian "deb822, after the security and source stanzas, before another"
rm "$WORK/apt/sources.list.d/debian.sources"
printf '# comment\ndeb-src http://src.example/debian bookworm main\ndeb [signed-by=/k.gpg arch=amd64] http://security.example/debian-security bookworm-security main\ndeb [signed-by=/k.gpg] http://list.example/debian bookworm main\n' >"$WORK/apt/sources.list"
expect_mirror http://list.example/debian "sources.list with options"
printf 'deb http://plain.example/debian bookworm main\n' >"$WORK/apt/sources.list"
expect_mirror http://plain.example/debian "sources.list without options"
[ "$(NCSERVO_DEBIAN_MIRROR=http://other.example/debian mirror)" = http://other.example/debian ] ||
  fail "NCSERVO_DEBIAN_MIRROR is not taken"
rm "$WORK/apt/sources.list"
rc=0; mirror 2>"$WORK/err" || rc=$?
[ "$rc" = 1 ] && grep -q "no Debian archive in $WORK/apt" "$WORK/err" || fail "no sources: exit $rc: $(cat "$WORK/err")"
! grep -q "deb.debian.org" "$SRC/.ci/debian-root.sh" || fail ".ci/debian-root.sh writes an archive's address"
echo PASS
