#!/usr/bin/env bash
# tshark_mutations.sh [-n MUTANTS] [-r "RATES"] [-s FIRST_SEED] [-k KEEP_DIR] BUILD_DIR
# Mutated copies of the bundled captures (slices of them) and of the real captures in
# ../shared/captures/real: `editcap -E RATE --seed S` at each rate (every other seed sparing the
# 14-byte Ethernet header, so the EtherCAT dissection is reached), snap-length truncations and
# files cut inside a record. Each goes through tshark with BUILD_DIR's plugin (-nVx, and -2 for
# every fourth) and through `ncservo validate`.
# Fails on a crash, an abort, a sanitizer report, a dissector bug, an exception thrown in the
# plugin (a "Malformed Packet: NCSERVO" item), a plugin warning or any other
# output on tshark's standard error (a cut file may only say that it was cut short), a run over
# the time limit, and a validate exit status other than 0, 3 or 4 (docs/cli.md, with
# --fail-on never). Failing mutants are kept in KEEP_DIR (default BUILD_DIR/tshark-mutations).
# MUTANTS (default 2) is per capture and rate; -n 100 makes several thousand.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
mutants=2 rates="0.001 0.01 0.05" first_seed=1 keep=""
while getopts "n:r:s:k:" opt; do
  case $opt in
    n) mutants=$OPTARG ;;
    r) rates=$OPTARG ;;
    s) first_seed=$OPTARG ;;
    k) keep=$OPTARG ;;
    *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
build=$(cd "${1:?usage: tshark_mutations.sh [-n N] [-r RATES] [-s SEED] [-k DIR] BUILD_DIR}" && pwd)
keep=${keep:-$build/tshark-mutations}
plugin="$build/plugin/ncservo.so" ncservo="$build/validator/ncservo"
run_tshark="$src/tests/tools/tshark-with-plugin.sh"
SRC=$src BUILD=$build
source "$src/tests/integration/lib.sh"  # skip, require_path, REAL_CAPTURES, and a WORK folder
work=$WORK
export WIRESHARK_ABORT_ON_DISSECTOR_BUG=1 WIRESHARK_ABORT_ON_TOO_MANY_ITEMS=1
limit=120  # seconds per run

# The bases: slices of the bundled captures (start-up, enabling, motion, faults) and every real one.
bases=()
for capture in "$src"/captures/*.pcap; do
  base="$work/base-$(basename "$capture")"
  editcap -r "$capture" "$base" 1-250 1650-1800 3400-3500 >/dev/null
  bases+=("$base")
done
if [ -e "$REAL_CAPTURES" ]; then
  for capture in "$REAL_CAPTURES"/*; do
    case $capture in *.pcap | *.pcapng | *.cap) bases+=("$capture") ;; esac
  done
fi

count=0 failed=0
# check NAME MUTANT CUT: runs tshark and validate on one mutant; CUT=1 allows "cut short".
check() {
  local name=$1 mutant=$2 cut=$3 two_pass=()
  count=$((count + 1))
  [ $((count % 4)) = 0 ] && two_pass=(-2)
  local why="" rc=0
  chmod a+r "$mutant"
  timeout $limit "$run_tshark" "$plugin" -nVx "${two_pass[@]}" -r "$mutant" >"$work/tshark.out" 2>"$work/tshark.err" || rc=$?
  if [ $rc = 124 ]; then
    why="tshark ran over ${limit} s"
  elif grep -qE "Malformed Packet: NCSERVO|Dissector bug, protocol NCSERVO" "$work/tshark.out"; then
    # The plugin reads within the captured bytes and marks short regions; it never throws.
    why="the plugin threw: $(grep -m1 -E "Malformed Packet: NCSERVO|Dissector bug, protocol NCSERVO" "$work/tshark.out")"
  elif [ $cut = 1 ] && [ $rc = 2 ] && grep -q "cut short in the middle of a packet" "$work/tshark.err" &&
    [ "$(grep -c . "$work/tshark.err")" -le 2 ]; then
    :
  elif [ $rc != 0 ]; then
    why="tshark exit $rc"
  elif [ -s "$work/tshark.err" ]; then
    why="tshark printed on standard error"
  fi
  if [ -z "$why" ]; then
    rc=0
    timeout $limit "$ncservo" validate --fail-on never --format json -o /dev/null "$mutant" \
      >/dev/null 2>"$work/validate.err" || rc=$?
    if [ $rc != 0 ] && [ $rc != 3 ] && [ $rc != 4 ]; then
      why="validate exit $rc"
    elif grep -qE "Sanitizer|runtime error" "$work/validate.err"; then
      why="validate sanitizer report"
    fi
  fi
  if [ -n "$why" ]; then
    failed=$((failed + 1))
    mkdir -p "$keep"
    cp "$mutant" "$keep/$name"
    cat "$work/tshark.err" "$work/validate.err" 2>/dev/null >"$keep/$name.err" || true
    echo "FAIL: $name: $why (kept in $keep/$name): $(grep -m3 . "$work/tshark.err" "$work/validate.err" 2>/dev/null | tr '\n' ' ')" >&2
  fi
}

for base in "${bases[@]}"; do
  stem=$(basename "$base")
  stem=${stem#base-}
  for rate in $rates; do
    for ((seed = first_seed; seed < first_seed + mutants; seed++)); do
      offset=$((seed % 2 ? 14 : 0))
      editcap -E "$rate" -o $offset --seed "$seed" "$base" "$work/mutant" >/dev/null 2>&1
      check "$stem-E$rate-o$offset-seed$seed" "$work/mutant" 0
    done
  done
  # Truncations: short snap lengths, and the file cut at a few places inside it.
  for snap in 16 24 30 42 60 100; do
    editcap -s $snap "$base" "$work/mutant" >/dev/null 2>&1
    check "$stem-s$snap" "$work/mutant" 0
  done
  size=$(stat -c %s "$base")
  for ((seed = first_seed; seed < first_seed + mutants; seed++)); do
    cut=$(((seed * 7919 + 13) * 104729 % size))
    head -c "$cut" "$base" >"$work/mutant"
    check "$stem-cut$cut" "$work/mutant" 1
  done
done
echo "tshark_mutations: $count mutants of ${#bases[@]} captures, $failed failed"
[ $failed = 0 ]
# Without the real captures the bundled ones' mutants have run, and the test says it skipped those.
require_path "$REAL_CAPTURES" "real captures" "the bundled captures' mutants passed"
