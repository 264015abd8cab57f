#!/usr/bin/env bash
# How fast `ncservo validate` reads compressed captures: the frame rate on the same simulated
# capture plain, zstd-compressed and gzip-compressed, run by run in turn, and the peak RSS of each.
# Goals: zstd at least 0.9x the plain frame rate, gzip at least 0.8x (each the median of the
#        run-by-run ratios against the plain run just before it); peak RSS under 32 MiB.
#
# Usage: tests/bench/compressed_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_DURATION  seconds of the simulated soak (default 600 = 1,200,000 frames)
#        NCSERVO_BENCH_RUNS      runs per capture (default 3)
#        NCSERVO_BENCH_CMD       ncservo arguments before the capture
#                                (default: validate --format json --output /dev/null)
#        NCSERVO_CAPTURE_READER  libpcap: every record through libpcap (docs/benchmarks.md
#                                "Reading captures"), to compare with the in-place reader
# The capture is `ncservo simulate --scenario soak --duration D --seed 1`, compressed with
# `zstd -3` and `gzip -6` (the tools' defaults; ncservo reads gzip through ISA-L); all three sit in the page cache, so the runs
# read from memory. The goals are reported PASS or MISS; the exit status is 0 whatever they are,
# and 1 when a tool fails to run. Needs GNU time (/usr/bin/time), zstd and gzip.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

duration=${NCSERVO_BENCH_DURATION:-600}
runs=${NCSERVO_BENCH_RUNS:-3}
read -r -a ncservo_args <<<"${NCSERVO_BENCH_CMD:-validate --format json --output /dev/null}"
goal_zstd=0.9 goal_gzip=0.8 goal_rss_mib=32

fail() { echo "compressed_ratio: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
/usr/bin/time --version 2>&1 | grep -q GNU || fail "GNU time (/usr/bin/time) is not installed"
command -v zstd >/dev/null || fail "zstd is not installed"
command -v gzip >/dev/null || fail "gzip is not installed"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# measure NAME CAPTURE: one run; appends its wall seconds and peak RSS (KiB) to $tmp/NAME
measure() {
  local start end status=0
  start=$(date +%s%N)
  /usr/bin/time -v -o "$tmp/time.txt" "$ncservo" "${ncservo_args[@]}" "$2" >/dev/null \
    2>"$tmp/stderr" || status=$?
  end=$(date +%s%N)
  # validate exits 1 on findings, 4 with no servo: results, not failures to run
  case $status in 0 | 1 | 4) ;; *) tail -5 "$tmp/stderr" >&2; fail "$1: exit $status" ;; esac
  echo "$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.6f", (b - a) / 1e9 }')" \
    "$(awk -F': ' '/Maximum resident set size/ { print $2 }' "$tmp/time.txt")" >>"$tmp/$1"
}

start_all=$(date +%s)
capture=$tmp/soak.pcap
"$ncservo" simulate --scenario soak --duration "$duration" --seed 1 -o "$capture" 2>"$tmp/sim.txt" ||
  fail "simulate failed: $(cat "$tmp/sim.txt")"
frames=$(grep -o 'wrote [0-9]*' "$tmp/sim.txt" | cut -d' ' -f2)
zstd -q -3 -c "$capture" >"$capture.zst"
gzip -6 -c "$capture" >"$capture.gz"
echo "ncservo: $ncservo ${ncservo_args[*]} CAPTURE"
echo "capture: $frames frames; plain $(($(stat -c %s "$capture") / 1000000)) MB," \
  "zstd $(($(stat -c %s "$capture.zst") / 1000000)) MB, gzip $(($(stat -c %s "$capture.gz") / 1000000)) MB"
echo "$runs runs each, in turn (plain, zstd, gzip); load average: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) CPUs"

for _ in $(seq "$runs"); do
  measure plain "$capture"
  measure zstd "$capture.zst"
  measure gzip "$capture.gz"
done

echo
printf '%-8s %9s %12s %13s  %s\n' capture "best s" frames/s "peak RSS MiB" "runs (s)"
for name in plain zstd gzip; do
  awk -v n="$name" -v f="$frames" '
    { s[NR] = $1; if (NR == 1 || $1 < best) best = $1; if ($2 > rss) rss = $2; all = all sprintf(" %.3f", $1) }
    END { printf "%-8s %9.3f %12.0f %13.2f %s\n", n, best, f / best, rss / 1024, all }' "$tmp/$name"
done

verdict() { if awk "BEGIN { exit !($1) }"; then echo PASS; else echo MISS; fi; }
# paired NAME GOAL: plain's time over NAME's, run by run, the median with the lowest and highest
paired() {
  local r median low high
  r=$(paste -d' ' "$tmp/plain" "$tmp/$1" | awk '
    { r[NR] = $1 / $3 }
    END {
      n = NR
      for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (r[j] < r[i]) { t = r[i]; r[i] = r[j]; r[j] = t }
      m = n % 2 ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2
      printf "%.3f %.3f %.3f", m, r[1], r[n]
    }')
  read -r median low high <<<"$r"
  printf '  %-40s %7sx  goal >= %-4s %s  (runs %s-%s)\n' "$1 frame rate / plain's (median)" "$median" \
    "${2}x" "$(verdict "$median >= $2")" "$low" "$high"
}
echo
echo "goals:"
paired zstd "$goal_zstd"
paired gzip "$goal_gzip"
for name in plain zstd gzip; do
  m=$(awk '$2 > r { r = $2 } END { printf "%.1f", r / 1024 }' "$tmp/$name")
  printf '  %-40s %7s   goal <  %-4s %s\n' "$name peak RSS (MiB)" "$m" "$goal_rss_mib" \
    "$(verdict "$m < $goal_rss_mib")"
done
echo "whole run: $(($(date +%s) - start_all)) s"
