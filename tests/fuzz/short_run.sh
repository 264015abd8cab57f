#!/usr/bin/env bash
# short_run.sh FUZZER SEEDS FUZZ_SRC SECONDS
# The test-suite run of one fuzz target: every saved crasher of tests/fuzz/crashers/<target>/
# must now pass, then SECONDS of fuzzing from the seed corpus (in a scratch copy) must find nothing.
set -euo pipefail
fuzzer=$1 seeds=$2 src=$3 seconds=$4
name=$(basename "$fuzzer")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TMPDIR=$work
shopt -s nullglob
crashers=("$src/crashers/$name"/*)
if [ ${#crashers[@]} -gt 0 ]; then
  "$fuzzer" -runs=1 "${crashers[@]}" >"$work/replay.log" 2>&1 || {
    tail -40 "$work/replay.log" >&2
    echo "FAIL: $name: a saved crasher fails again" >&2
    exit 1
  }
fi
dict=()
[ -f "$src/${name#fuzz_}.dict" ] && dict=(-dict="$src/${name#fuzz_}.dict")
mkdir "$work/corpus" "$work/artifacts"
set +e
"$fuzzer" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$work/artifacts/" "${dict[@]}" \
  "$work/corpus" "$seeds" >"$work/fuzz.log" 2>&1
rc=$?
set -e
if [ $rc != 0 ] || [ -n "$(ls "$work/artifacts")" ]; then
  grep -v '^#' "$work/fuzz.log" | tail -60 >&2
  for a in "$work/artifacts"/*; do echo "crasher: $(basename "$a"): $(base64 -w0 "$a" | head -c 400)" >&2; done
  echo "FAIL: $name exited $rc; reproduce with tests/fuzz/long_run.sh" >&2
  exit 1
fi
grep -E '^stat::number_of_executed_units|^#[0-9]+ +DONE' "$work/fuzz.log" | tr '\n' ' '
echo
echo "$name: ${seconds} s clean"
