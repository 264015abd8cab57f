#!/usr/bin/env bash
# clang_format.sh SRC BUILD: every C++ file under validator/, plugin/ and tests/ is as clang-format
# (Debian 12's, with the root's .clang-format) writes it; each one that is not is named with its
# first differences. Without clang-format: exit 77 with the reason (under CI: fails).
# Another major version of clang-format lays some constructs out otherwise (a lambda among call
# arguments, `struct stat info {}`, comments after non-ASCII text), so a tree cannot satisfy two:
# with another one the test says so and exits 77, also under CI, whose Debian 12 part checks.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program clang-format
reference_major=14  # Debian 12's clang-format, the one the sources are formatted with
major=$(clang-format --version | sed -n 's/.*clang-format version \([0-9]*\)\..*/\1/p')
if [ "$major" != "$reference_major" ]; then
  echo "SKIPPED: clang-format $major is not the sources' formatter ($reference_major, Debian 12's);" \
    "the Debian 12 run checks the format"
  exit 77
fi
cd "$SRC"
mapfile -d '' files < <(find validator plugin tests -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -print0 | sort -z)
[ ${#files[@]} -gt 0 ] || fail "no C++ file under validator/, plugin/ or tests/"
clang-format --dry-run --Werror "${files[@]}" >"$WORK/format.txt" 2>&1 || {
  grep -o '^[^:]*\.[ch]pp\|^[^:]*\.h' "$WORK/format.txt" | sort -u >&2
  fail "not clang-formatted (clang-format -i FILE): $(head -30 "$WORK/format.txt")"
}
echo "clang_format: ${#files[@]} files as $(clang-format --version | head -1) writes them"
