#!/usr/bin/env bash
# simulate_images.sh SRC BUILD
# Every process-image style of `ncservo simulate --image` (docs/protocol.md §9), with and without
# the start-up, plain, behind an ESL probe (docs/protocol.md §8), compressed by the output's name:
# `ncservo validate --config` with the layout file simulate wrote passes with every axis, and so
# do the ENI file and (with a start-up) the layout learned from it; the stock dissector reads the
# uncompressed capture without complaint.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
# name | axes | simulate options | output file
cases=(
  "soem|3|--image soem|soem.pcapng.zst"
  "soem, no start-up, probe|3|--image soem --no-startup --probe esl|soem-probe.pcap.gz"
  "etherlab with terminals|4|--image etherlab --io-slaves 3|etherlab.pcap.gz"
  "etherlab, probe|2|--image etherlab --probe esl|etherlab-probe.pcapng.zst"
  "mixed, per slave|3|--image mixed --seed 1|mixed.pcapng.zst"
  "mixed, outputs first, probe|5|--image mixed --seed 2 --probe esl|mixed-probe.pcapng.zst"
  "mixed, no start-up|8|--image mixed --no-startup --seed 3|mixed-nostartup.pcap.gz"
  "twincat|4|--image twincat|twincat.pcapng.zst"
  "twincat, two frames, probe|30|--image twincat --io-slaves 6 --probe esl|twincat-probe.pcapng.zst"
  "twincat, no start-up|1|--image twincat --no-startup|twincat-nostartup.pcap"
  "--layout interleaved alias|3|--layout interleaved --io-slaves 2|alias.pcap"
)
for row in "${cases[@]}"; do
  IFS='|' read -r name axes args file <<<"$row"
  read -r -a opts <<<"$args"
  cap="$WORK/$file"
  "$NCSERVO" simulate "${opts[@]}" --axes "$axes" --duration 2 -o "$cap" \
    --layout-config "$WORK/layout.toml" --eni "$WORK/eni.xml" 2>"$WORK/sim.err" ||
    fail "$name: simulate exit $?: $(cat "$WORK/sim.err")"
  case "$file" in
    *.zst) [ "$(head -c 4 "$cap" | od -An -tx1 | tr -d ' ')" = 28b52ffd ] || fail "$name: not zstd" ;;
    *.gz) [ "$(head -c 2 "$cap" | od -An -tx1 | tr -d ' ')" = 1f8b ] || fail "$name: not gzip" ;;
  esac
  sources=(config eni)
  [[ "$args" == *--no-startup* ]] || sources+=(startup)
  for source in "${sources[@]}"; do
    case $source in
      config) layout=(--config "$WORK/layout.toml") ;;
      eni) layout=(--eni "$WORK/eni.xml") ;;
      startup) layout=() ;;
    esac
    "$NCSERVO" validate "${layout[@]}" --fail-on info "$cap" >"$WORK/report.txt" ||
      fail "$name, $source: validate exit $?: $(grep -v '^  ' "$WORK/report.txt" | head -20)"
    grep -q "^verdict: PASS - 0 errors, 0 warnings, 0 info" "$WORK/report.txt" ||
      fail "$name, $source: $(tail -1 "$WORK/report.txt")"
    grep -q "^layout: $source, $axes ax" "$WORK/report.txt" ||
      fail "$name, $source: $(grep '^layout' "$WORK/report.txt"), expected $axes axes"
    if [[ "$args" == *--probe* ]]; then
      grep -q "^timestamps: probe" "$WORK/report.txt" ||
        fail "$name, $source: $(grep '^timestamps' "$WORK/report.txt" || echo 'no timestamps line')"
    fi
  done
  # The stock dissector on the plain capture (the probe's ESL header needs its heuristic).
  if [[ "$args" != *--probe* ]]; then
    "$NCSERVO" simulate "${opts[@]}" --axes "$axes" --duration 2 --compress none \
      -o "$WORK/plain.pcap" 2>/dev/null
    chmod a+r "$WORK/plain.pcap"
    "$TSHARK" none -r "$WORK/plain.pcap" -Y "_ws.malformed || _ws.expert" -T fields \
      -e frame.number >"$WORK/stock.txt" 2>"$WORK/tshark.err" ||
      fail "$name: tshark exit $?: $(cat "$WORK/tshark.err")"
    [ ! -s "$WORK/stock.txt" ] ||
      fail "$name: the stock dissector flags frames $(head -c 200 "$WORK/stock.txt" | tr '\n' ' ')"
  fi
done

# -o - with --compress: the stream is compressed as asked.
"$NCSERVO" simulate --image twincat --duration 1 --compress zstd -o - >"$WORK/stdout.zst"
[ "$(head -c 4 "$WORK/stdout.zst" | od -An -tx1 | tr -d ' ')" = 28b52ffd ] ||
  fail "--compress zstd -o -: not zstd"
"$NCSERVO" validate --fail-on warning "$WORK/stdout.zst" >/dev/null ||
  fail "--compress zstd -o -: validate exit $?"
# --image and its older name --layout exclude each other; unknown styles are refused.
for args in "--image mixed --layout default" "--image sercos" "--probe et1000" "--compress xz"; do
  read -r -a argv <<<"$args"
  set +e
  "$NCSERVO" simulate "${argv[@]}" -o "$WORK/x.pcap" >/dev/null 2>"$WORK/err.txt"
  rc=$?
  set -e
  [ "$rc" = 2 ] || fail "simulate $args: exit $rc, expected 2"
done
"$NCSERVO" simulate --help >"$WORK/help.txt"
for word in --image soem etherlab mixed twincat --probe esl --compress gzip zstd --layout; do
  grep -qF -- "$word" "$WORK/help.txt" || fail "simulate --help does not mention $word"
done
echo "simulate_images: ${#cases[@]} set-ups validate with their layout file, ENI and start-up"
