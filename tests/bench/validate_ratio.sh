#!/usr/bin/env bash
# How fast and how small `ncservo validate` is: on a generated 8-axis capture, its frame rate
# against a bare libpcap loop that only reads the same file (a tiny C program built here) and
# against stock tshark (no plugin) extracting `ecat.cmd`, all in one run; the same against the bare
# loop on the same capture written as pcapng (libpcap reads both); and its peak memory on a
# 500,000-frame and a 2,000,000-frame capture.
# Goals: at least 1.0x the bare loop's frame rate, for pcap and for pcapng; at least 30x tshark's
#        frame rate; peak RSS under 32 MiB for 500,000 frames and for 2,000,000 frames alike.
#
# Usage: tests/bench/validate_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_CYCLES        cycles of the main capture (default 250000 = 500,000 frames)
#        NCSERVO_BENCH_LARGE         0 skips the large capture (default 1)
#        NCSERVO_BENCH_PCAPNG        0 skips the pcapng capture (default 1)
#        NCSERVO_CAPTURE_READER      libpcap: ncservo reads every record through libpcap, as before
#                                    its in-place reader (docs/benchmarks.md "Reading captures")
#        NCSERVO_BENCH_LARGE_CYCLES  cycles of the large capture (default 1000000 = 2,000,000 frames)
#        NCSERVO_BENCH_TSHARK_FRAMES tshark reads only this many first frames, 0 = all (default 0);
#                                    its rate then includes its start-up (about 0.3 s) over fewer frames
#        NCSERVO_BENCH_RUNS          runs per measurement (default 3): best wall time, highest RSS;
#                                    against the bare loop, the median of the run pairs' ratios
#        NCSERVO_BENCH_CMD           ncservo arguments before the capture
#                                    (default: validate --format json --output /dev/null)
#        NCSERVO_BENCH_TIMER         gnu (GNU time for the peak RSS, date for the wall time) or c
#                                    (a small fork/wait4 timer built here); default gnu if installed
# Each cycle is two frames (master and returned copy). Captures come from
# tests/tools/gen_capture.py --axes 8 --seed 3 --enable-by 2048 (every axis enabled within the
# learning window, so validate infers the layout with no configuration, as a user runs it; a
# tenth of the cycles when fewer than 20,480) and sit
# in the page cache (just written), so every tool reads from memory. The bare loop and ncservo take turns, run by run, so that a change in
# the load of a busy machine falls on both alike; the load average is printed since the
# machine may be busy. The goals are reported PASS or MISS; the exit status is 0 whatever they
# are, and 1 when a tool fails to build or run.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

cycles=${NCSERVO_BENCH_CYCLES:-250000}
large=${NCSERVO_BENCH_LARGE:-1}
pcapng=${NCSERVO_BENCH_PCAPNG:-1}
large_cycles=${NCSERVO_BENCH_LARGE_CYCLES:-1000000}
tshark_frames=${NCSERVO_BENCH_TSHARK_FRAMES:-0}
runs=${NCSERVO_BENCH_RUNS:-3}
default_cmd="validate --format json --output /dev/null"
read -r -a ncservo_args <<<"${NCSERVO_BENCH_CMD:-$default_cmd}"
runner=$root/tests/tools/tshark-with-plugin.sh
goal_bare=1.0 goal_tshark=30 goal_rss_mib=32

fail() { echo "validate_ratio: $*" >&2; exit 1; }

[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
command -v tshark >/dev/null || fail "tshark is not installed"
command -v cc >/dev/null || fail "no C compiler (cc)"

# Until `ncservo validate` exists, `decode` stands in so that the script itself can be tried.
# (CLI11 answers `ncservo validate --help` with the top-level help when there is no such
# subcommand, so look for the subcommand's own usage line.)
if [ "${ncservo_args[0]}" = validate ] &&
   ! "$ncservo" validate --help 2>&1 | grep -q '^Usage: .* validate'; then
  echo "NOTE: this ncservo has no 'validate' subcommand; timing 'decode --format csv' as a"
  echo "      stand-in: the ncservo numbers and goals below are the stand-in's, not validate's."
  ncservo_args=(decode --format csv)
fi
ncservo_name="ncservo ${ncservo_args[0]}"
# validate exits 1 when it finds something: a result, not a failure to run
if [ "${ncservo_args[0]}" = validate ]; then ncservo_ok="0 1"; else ncservo_ok="0"; fi

timer=${NCSERVO_BENCH_TIMER:-}
if [ -z "$timer" ]; then
  if /usr/bin/time --version 2>&1 | grep -q 'GNU'; then timer=gnu; else timer=c; fi
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
chmod a+rx "$tmp"  # as root the tshark runner drops to user nobody, who must read the captures

# The bare loop: open, read every frame, count frames and captured bytes (so that the loop
# has a result and is not optimised away), print them.
cat >"$tmp/bare_loop.c" <<'EOF'
#include <pcap/pcap.h>
#include <stdio.h>

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: bare_loop CAPTURE\n");
    return 2;
  }
  char err[PCAP_ERRBUF_SIZE];
  pcap_t *p = pcap_open_offline_with_tstamp_precision(argv[1], PCAP_TSTAMP_PRECISION_NANO, err);
  if (!p) {
    fprintf(stderr, "bare_loop: %s\n", err);
    return 1;
  }
  struct pcap_pkthdr *hdr;
  const u_char *data;
  unsigned long long frames = 0, bytes = 0;
  int rc;
  while ((rc = pcap_next_ex(p, &hdr, &data)) == 1) {
    frames++;
    bytes += hdr->caplen;
  }
  if (rc == PCAP_ERROR) {
    fprintf(stderr, "bare_loop: %s\n", pcap_geterr(p));
    return 1;
  }
  pcap_close(p);
  printf("%llu %llu\n", frames, bytes);
  return 0;
}
EOF
pcap_flags=$(pkg-config --cflags --libs libpcap 2>/dev/null || echo -lpcap)
# shellcheck disable=SC2086  # pkg-config output is a list of flags
cc -O2 -Wall -o "$tmp/bare_loop" "$tmp/bare_loop.c" $pcap_flags ||
  fail "could not build the bare libpcap loop (libpcap-dev installed?)"

# The fallback timer, when GNU time is missing: fork, exec, wait4; wall time in ns, the
# child's peak RSS in KiB. (Not Python: a child forked from Python carries Python's ~10 MiB
# into its ru_maxrss, which exec keeps.)
cat >"$tmp/timer.c" <<'EOF'
#include <stdio.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: timer OUT COMMAND [ARGS...]\n");
    return 2;
  }
  struct timespec start, end;
  clock_gettime(CLOCK_MONOTONIC, &start);
  pid_t pid = fork();
  if (pid < 0) {
    perror("timer: fork");
    return 2;
  }
  if (pid == 0) {
    execvp(argv[2], argv + 2);
    perror(argv[2]);
    _exit(127);
  }
  int status;
  struct rusage usage;
  if (wait4(pid, &status, 0, &usage) < 0) {
    perror("timer: wait4");
    return 2;
  }
  clock_gettime(CLOCK_MONOTONIC, &end);
  FILE *out = fopen(argv[1], "w");
  if (!out) {
    perror(argv[1]);
    return 2;
  }
  fprintf(out, "%.6f %ld\n",
          (double)(end.tv_sec - start.tv_sec) + (end.tv_nsec - start.tv_nsec) / 1e9,
          usage.ru_maxrss);
  fclose(out);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}
EOF
if [ "$timer" = c ]; then
  cc -O2 -Wall -o "$tmp/timer" "$tmp/timer.c" || fail "could not build the fallback timer"
fi

# measure OUT ARGS...: runs ARGS once, stdout discarded and stderr to $tmp/stderr, and writes
# "SECONDS KIB" to OUT; returns ARGS' exit status. GNU time's %e has only 10 ms resolution,
# too coarse for the bare loop, so with it the wall time comes from date around the run.
measure() {
  local out=$1 start end status=0
  shift
  if [ "$timer" = gnu ]; then
    start=$(date +%s%N)
    /usr/bin/time -f '%M' -o "$out.rss" "$@" >/dev/null 2>"$tmp/stderr" || status=$?
    end=$(date +%s%N)
    echo "$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.6f", (b - a) / 1e9 }')" \
      "$(tail -n1 "$out.rss")" >"$out"
  else
    "$tmp/timer" "$out" "$@" >/dev/null 2>"$tmp/stderr" || status=$?
  fi
  return "$status"
}

# once NAME OK_STATUSES ARGS...: one run; keeps the best wall time, highest RSS and every time
declare -A best_s peak_kib times
once() {
  local name=$1 ok=$2 status=0 secs kib
  shift 2
  measure "$tmp/m" "$@" || status=$?
  if ! [[ " $ok " == *" $status "* ]]; then
    echo "validate_ratio: $name failed (exit $status): $*" >&2
    tail -n 20 "$tmp/stderr" >&2
    exit 1
  fi
  read -r secs kib <"$tmp/m"
  times[$name]+="${times[$name]:+ }$(printf '%.3f' "$secs")"
  if [ -z "${best_s[$name]:-}" ] || awk -v a="$secs" -v b="${best_s[$name]}" 'BEGIN { exit !(a < b) }'; then
    best_s[$name]=$secs
  fi
  if [ "$kib" -gt "${peak_kib[$name]:-0}" ]; then peak_kib[$name]=$kib; fi
}
# row NAME FRAMES: appends the runs of NAME as a row to $tmp/table, and forgets them
row() {
  printf '%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "${best_s[$1]}" "${peak_kib[$1]}" "${times[$1]}" \
    >>"$tmp/table"
  unset "best_s[$1]" "peak_kib[$1]" "times[$1]"
}
# bench NAME FRAMES OK_STATUSES ARGS...: $runs runs; appends a row to $tmp/table
bench() {
  local name=$1 frames=$2 ok=$3
  shift 3
  for _ in $(seq "$runs"); do once "$name" "$ok" "$@"; done
  row "$name" "$frames"
}
# against_bare CAPTURE FRAMES [SUFFIX]: the bare loop and ncservo take turns, so that a change in
# the machine's load falls on both alike; SUFFIX tells the rows of another file format apart
against_bare() {
  for _ in $(seq "$runs"); do
    once "$bare_name${3:-}" 0 "$tmp/bare_loop" "$1"
    once "$ncservo_name${3:-}" "$ncservo_ok" "$ncservo" "${ncservo_args[@]}" "$1"
  done
  row "$bare_name${3:-}" "$2"
  row "$ncservo_name${3:-}" "$2"
}

# rate NAME FRAMES: frames per second of that row
rate() {
  awk -F'\t' -v n="$1" -v f="$2" '$1 == n && $2 == f { printf "%.1f", $2 / $3 }' "$tmp/table"
}
rss_mib() {
  awk -F'\t' -v n="$1" -v f="$2" '$1 == n && $2 == f { printf "%.1f", $4 / 1024 }' "$tmp/table"
}

# capture CYCLES FILE [FORMAT]: generates it (pcap, or FORMAT), prints its size
capture() {
  local start end enable_by=$(($1 / 10 < 2048 ? $1 / 10 : 2048))
  start=$(date +%s)
  python3 "$root/tests/tools/gen_capture.py" --axes 8 --cycles "$1" --seed 3 --enable-by "$enable_by" \
    --format "${3:-pcap}" -o "$2" ||
    fail "gen_capture.py --cycles $1 failed"
  chmod a+r "$2"
  end=$(date +%s)
  echo "capture: $((2 * $1)) frames, 8 axes, ${3:-pcap}, $(($(stat -c %s "$2") / 1000000)) MB," \
    "generated in $((end - start)) s"
}

# check_count FILE FRAMES: the bare loop must see every frame
check_count() {
  local got
  got=$("$tmp/bare_loop" "$1" | cut -d' ' -f1) || fail "the bare loop could not read $1"
  [ "$got" = "$2" ] || fail "the bare loop read $got frames of $1, expected $2"
}

bare_name="bare libpcap loop"
tshark_name="tshark -T fields -e ecat.cmd"
frames=$((2 * cycles))
echo "ncservo: $ncservo ${ncservo_args[*]} CAPTURE"
echo "timer: $timer; $runs runs each, best wall time and highest peak RSS;" \
  "load average: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) CPUs"
script_start=$(date +%s)
: >"$tmp/table"

cap=$tmp/main.pcap
capture "$cycles" "$cap"
check_count "$cap" "$frames"
against_bare "$cap" "$frames"
if [ "$tshark_frames" -gt 0 ] && [ "$tshark_frames" -lt "$frames" ]; then
  echo "tshark reads only the first $tshark_frames frames (-c); frame rates are compared"
  bench "$tshark_name" "$tshark_frames" 0 "$runner" none -r "$cap" -c "$tshark_frames" \
    -T fields -e ecat.cmd
  tshark_count=$tshark_frames
else
  bench "$tshark_name" "$frames" 0 "$runner" none -r "$cap" -T fields -e ecat.cmd
  tshark_count=$frames
fi
rm -f "$cap"

if [ "$pcapng" != 0 ]; then
  cap=$tmp/main.pcapng
  capture "$cycles" "$cap" pcapng
  check_count "$cap" "$frames"
  against_bare "$cap" "$frames" " (pcapng)"
  rm -f "$cap"
fi

if [ "$large" != 0 ]; then
  large_frames=$((2 * large_cycles))
  cap=$tmp/large.pcap
  capture "$large_cycles" "$cap"
  check_count "$cap" "$large_frames"
  against_bare "$cap" "$large_frames"
  rm -f "$cap"
fi

echo
printf '%-30s %9s %9s %12s %13s  %s\n' tool frames "best s" frames/s "peak RSS MiB" "runs (s)"
while IFS=$'\t' read -r name n secs kib all; do
  printf '%-30s %9d %9.3f %12.0f %13.1f  %s\n' "$name" "$n" "$secs" \
    "$(awk -v n="$n" -v s="$secs" 'BEGIN { printf "%.1f", n / s }')" \
    "$(awk -v k="$kib" 'BEGIN { printf "%.2f", k / 1024 }')" "$all"
done <"$tmp/table"

echo
echo "goals ($ncservo_name):"
verdict() { # verdict CONDITION(awk) -> PASS or MISS
  if awk "BEGIN { exit !($1) }"; then echo PASS; else echo MISS; fi
}
# paired_line LABEL FRAMES GOAL [SUFFIX]: the bare loop's time over ncservo's, run pair by run pair
# (they took turns), the median of those ratios, with the lowest and highest
paired_line() {
  local r
  r=$(awk -F'\t' -v f="$2" -v bare="$bare_name${4:-}" -v nc="$ncservo_name${4:-}" '
    $2 == f && $1 == bare { nb = split($5, b, " ") }
    $2 == f && $1 == nc { split($5, n, " ") }
    END {
      for (i = 1; i <= nb; i++) r[i] = b[i] / n[i]
      for (i = 1; i <= nb; i++) for (j = i + 1; j <= nb; j++) if (r[j] < r[i]) { t = r[i]; r[i] = r[j]; r[j] = t }
      m = nb % 2 ? r[(nb + 1) / 2] : (r[nb / 2] + r[nb / 2 + 1]) / 2
      printf "%.3f %.3f %.3f", m, r[1], r[nb]
    }' "$tmp/table")
  read -r median low high <<<"$r"
  printf '  %-52s %8sx  goal >= %-5s %s  (pairs %s-%s)\n' "$1" "$median" "${3}x" \
    "$(verdict "$median >= $3")" "$low" "$high"
}
ratio_line() { # ratio_line LABEL NCSERVO_FRAMES OTHER_NAME OTHER_FRAMES GOAL
  local r
  r=$(awk -v a="$(rate "$ncservo_name" "$2")" -v b="$(rate "$3" "$4")" \
    'BEGIN { printf "%.3f", a / b }')
  printf '  %-52s %8sx  goal >= %-5s %s\n' "$1" "$r" "${5}x" "$(verdict "$r >= $5")"
}
rss_line() { # rss_line FRAMES
  local m
  m=$(rss_mib "$ncservo_name" "$1")
  printf '  %-52s %8s   goal <  %-5s %s\n' "peak RSS, $1 frames (MiB)" "$m" "$goal_rss_mib" \
    "$(verdict "$m < $goal_rss_mib")"
}
paired_line "frame rate / bare loop's, $frames frames (median)" "$frames" "$goal_bare"
if [ "$pcapng" != 0 ]; then
  paired_line "frame rate / bare loop's, pcapng, $frames frames (median)" "$frames" "$goal_bare" \
    " (pcapng)"
fi
if [ "$large" != 0 ]; then
  paired_line "frame rate / bare loop's, $large_frames frames (median)" "$large_frames" \
    "$goal_bare"
fi
ratio_line "frame rate / tshark's ($tshark_count frames)" "$frames" "$tshark_name" \
  "$tshark_count" "$goal_tshark"
rss_line "$frames"
if [ "$large" != 0 ]; then
  rss_line "$large_frames"
else
  echo "  (the large capture was skipped: NCSERVO_BENCH_LARGE=0)"
fi
echo "whole run: $(($(date +%s) - script_start)) s"
