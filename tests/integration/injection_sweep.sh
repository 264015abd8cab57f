#!/usr/bin/env bash
# injection_sweep.sh SRC BUILD [SEEDS]
# Every rule the independent generator can inject, once per seed, each time in another set-up:
# 1-8 axes, Ethernet/VLAN/QinQ/UDP framing, pcap or pcapng, Servo_Ready_Mode 0 or 1, the
# violation at another time and on another axis. `ncservo validate` must report exactly what the
# generator says the injection produces (rule, axis, a frame inside its window, companions).
# validate_injected.sh checks each rule in one fixed set-up with the plugin too; this varies the
# set-up. In the suite with one seed (25 captures); more seeds for a longer run.
SRC=$1 BUILD=$2 SEEDS=${3:-1}
source "$SRC/tests/integration/lib.sh"
# The generator's rules in the order of the rule table.
mapfile -t injectable < <(python3 "$GEN" --list-rules)
mapfile -t station_rules < <(python3 "$GEN" --list-station-rules)
RULES=()
for rule in $("$NCSERVO" rules | awk '{ print $1 }'); do
  if [[ " ${injectable[*]} " == *" $rule "* ]]; then RULES+=("$rule"); fi
done
[ ${#RULES[@]} -gt 0 ] || fail "no rule both in \`ncservo rules\` and in gen_capture.py --list-rules"
ENCAPS=(eth vlan qinq udp)
FORMATS=(pcap pcapng)

cases=0 failures=0
for seed in $(seq 1 "$SEEDS"); do
  for rule in "${RULES[@]}"; do
    cases=$((cases + 1))
    axes=$(((seed * 7 + cases) % 8 + 1))
    axis=$((cases % axes))
    # The generator's constraints: ZP-001 on an incremental axis (odd index), ZP-003 on an
    # absolute one (even index); a COM rule concerns the whole frame.
    case $rule in
      ZP-001) [ "$axes" -ge 2 ] || axes=2; axis=$(((axis | 1) < axes ? (axis | 1) : 1)) ;;
      ZP-003) axis=$((axis & ~1)) ;;
    esac
    at=$(awk -v s="$seed" -v c="$cases" 'BEGIN { printf "%.2f", 0.6 + ((s * 37 + c * 11) % 70) / 100 }')
    inject="$rule@$at:$axis"
    [[ $rule == COM-* ]] && inject="$rule@$at"
    encap=${ENCAPS[$(((seed + cases) % 4))]}
    format=${FORMATS[$((cases % 2))]}
    ready=$(((seed + cases) % 2))
    setup="$inject, $axes axes, $encap, $format, Servo_Ready_Mode $ready, seed $seed"
    python3 "$GEN" --axes "$axes" --cycles $((2500 + seed * 100)) --seed $((seed * 1000 + cases)) \
      --encap "$encap" --format "$format" --ready-mode "$ready" --inject "$inject" \
      -o "$WORK/capture.$format" --findings "$WORK/expected.json" \
      --layout-config "$WORK/layout.toml" >"$WORK/gen.log" 2>&1 ||
      fail "generator ($setup): $(tail -1 "$WORK/gen.log")"
    # A rule judged on the axis whose drive said it needs the layout's stations.
    layout=()
    [[ " ${station_rules[*]} " == *" $rule "* ]] && layout=(--config "$WORK/layout.toml")
    set +e
    "$NCSERVO" validate --format json --servo-ready-mode "$ready" "${layout[@]}" \
      "$WORK/capture.$format" >"$WORK/report.json" 2>"$WORK/err.txt"
    rc=$?
    set -e
    if { [ $rc != 0 ] && [ $rc != 1 ]; } ||
       ! python3 "$SRC/tests/tools/check_findings.py" "$WORK/report.json" "$WORK/expected.json" \
         >"$WORK/check.txt" 2>&1; then
      failures=$((failures + 1))
      echo "MISMATCH ($setup): exit $rc; $(head -3 "$WORK/check.txt" "$WORK/err.txt" | tr '\n' ' ')" >&2
    fi
  done
done
[ "$failures" = 0 ] || fail "$failures of $cases injections not reported as the generator says"
echo "injection_sweep: $cases injections in varied set-ups, each reported as injected"
