#!/usr/bin/env bash
# long_run.sh [-m MINUTES] [-b BUILD_DIR] [TARGET...]
# Long fuzzing runs, one target after the other (default: all four, 10 minutes each, build-asan/).
# The corpus grows in BUILD_DIR/fuzz-corpus/TARGET and is kept between runs; a crasher is
# minimised and saved as tests/fuzz/crashers/TARGET/<name>, which the test suite's short run then
# replays. Prints executions, coverage and peak memory per target. Run it under nice on a shared
# machine: nice -n 15 tests/fuzz/long_run.sh
set -euo pipefail
src=$(cd "$(dirname "$0")" && pwd)
minutes=10
build="$src/../../build-asan"
while getopts "m:b:" opt; do
  case $opt in
    m) minutes=$OPTARG ;;
    b) build=$OPTARG ;;
    *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_frame fuzz_sequence fuzz_capture fuzz_config fuzz_mailbox)
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for target in "${targets[@]}"; do
  fuzzer="$build/tests/fuzz/$target"
  [ -x "$fuzzer" ] || { echo "long_run.sh: no $fuzzer (cmake --preset asan && cmake --build --preset asan)" >&2; exit 2; }
  short=${target#fuzz_}
  corpus="$build/fuzz-corpus/$target" artifacts="$build/fuzz-artifacts/$target"
  mkdir -p "$corpus" "$artifacts"
  export TMPDIR="$build/fuzz-tmp"
  mkdir -p "$TMPDIR"
  dict=()
  [ -f "$src/$short.dict" ] && dict=(-dict="$src/$short.dict")
  log="$build/fuzz-long-$target.log"
  set +e
  "$fuzzer" -max_total_time=$((minutes * 60)) -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" "${dict[@]}" "$corpus" "$build/tests/fuzz/seeds/$short" >"$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log")
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' "$log" | tail -1)
  echo "$target: ${minutes} min, exit $rc, ${execs:-?} executions, ${cov:-no coverage line}, peak RSS ${rss:-?} MB"
  for crash in "$artifacts"/crash-* "$artifacts"/timeout-* "$artifacts"/oom-* "$artifacts"/leak-*; do
    [ -f "$crash" ] || continue
    status=1
    saved="$src/crashers/$target/$(basename "$crash")"
    mkdir -p "$(dirname "$saved")"
    "$fuzzer" -minimize_crash=1 -runs=20000 -exact_artifact_path="$saved" "$crash" >"$log.min" 2>&1 || true
    [ -f "$saved" ] || cp "$crash" "$saved"
    echo "  crasher $(basename "$crash") minimised to $saved ($(stat -c %s "$saved") bytes)"
    mkdir -p "$artifacts/saved"
    mv "$crash" "$artifacts/saved/"
  done
done
exit $status
