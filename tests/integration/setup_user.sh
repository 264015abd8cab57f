#!/usr/bin/env bash
# setup_user.sh SRC BUILD: `.ci/setup --user` (README) asks only for what building and running
# the CLI and the plugin need, a subset of the full set-up's packages with no test, browser or
# sanitizer tooling, all of them Debian packages of this release; and the build it configures
# (tests off) needs none of the test libraries.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$SRC/.ci/setup" --user --list >"$WORK/user" || fail ".ci/setup --user --list exited $?"
"$SRC/.ci/setup" --list >"$WORK/all" || fail ".ci/setup --list exited $?"
sort -u "$WORK/user" -o "$WORK/user"
sort -u "$WORK/all" -o "$WORK/all"
extra=$(comm -23 "$WORK/user" "$WORK/all")
[ -z "$extra" ] || fail "--user asks for packages the full set-up does not: $extra"
for needed in tshark wireshark-dev cmake build-essential libfmt-dev libjs-chart.js libcpp-httplib-dev libmosquitto-dev; do
  grep -qx "$needed" "$WORK/user" || fail "--user lacks $needed"
done
for left in libgtest-dev libgmock-dev chromium clang npm python3-selenium libbenchmark-dev clang-format; do
  ! grep -qx "$left" "$WORK/user" || fail "--user installs $left, which only the test suite needs"
done
echo "ok --user: $(wc -l <"$WORK/user") packages of the full set-up's $(wc -l <"$WORK/all")"
# The tree --user configures: no test target, so nothing of GoogleTest is looked for.
cmake -S "$SRC" -B "$WORK/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNCSERVO_BUILD_TESTS=OFF \
  >"$WORK/cmake.log" 2>&1 || fail "configuring without tests: $(tail -5 "$WORK/cmake.log")"
! grep -qi 'gtest' "$WORK/build/CMakeCache.txt" || fail "configured without tests, it still looks for GoogleTest"
cmake --build "$WORK/build" --target help >"$WORK/targets" || fail "no targets"
grep -q ' ncservo_cli\| ncservo$' "$WORK/targets" || fail "no CLI target: $(head "$WORK/targets")"
! grep -q 'ncservo_unit_tests' "$WORK/targets" || fail "a unit-test target without tests"
echo "setup_user: --user needs a subset of the packages, and its build no test library"
