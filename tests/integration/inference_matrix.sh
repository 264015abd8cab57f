#!/usr/bin/env bash
# inference_matrix.sh SRC BUILD [EVERY]: the whole matrix. For every process-image style x
# {start-up captured, cut away} x {plain pcap, ESL probe pcapng, gzip, zstd}, with 1-8 axes and
# injected faults, `validate` with no configuration reports exactly what it reports with the
# simulator's exact layout file, frame for frame (JSON Lines, byte for byte); the layout comes
# from the start-up, or is inferred where the start-up was cut away; the injected faults fired.
# Every EVERY-th case (default 3) also runs tshark -2 with the plugin, with and without the
# configuration, and compares every PDO field and expert message of every frame.
SRC=$1 BUILD=$2
EVERY=${3:-3}
source "$SRC/tests/integration/lib.sh"

case_number=0
for image in soem etherlab mixed twincat; do
  for startup in with cut; do
    for kind in plain esl gzip zstd; do
      case_number=$((case_number + 1))
      axes=$(((case_number * 3) % 8 + 1))
      name="$image, start-up $startup, $kind, $axes ax"
      options=(--scenario soak --duration 3 --image "$image" --axes "$axes" --seed "$case_number"
               --fault SE-001@1.5:0 --fault MSG-001@2.0)
      [ "$startup" = cut ] && options+=(--no-startup)
      case $kind in
        plain) cap="$WORK/c$case_number.pcap" ;;
        esl) cap="$WORK/c$case_number.pcapng"; options+=(--probe esl) ;;
        gzip) cap="$WORK/c$case_number.pcap.gz" ;;
        zstd) cap="$WORK/c$case_number.pcapng.zst" ;;
      esac
      "$NCSERVO" simulate "${options[@]}" -o "$cap" --layout-config "$WORK/layout.toml" 2>/dev/null ||
        fail "$name: simulate exit $?"
      chmod a+r "$cap" "$WORK/layout.toml"
      "$NCSERVO" validate --format jsonl --fail-on never "$cap" >"$WORK/free.jsonl" ||
        fail "$name: validate exit $?"
      "$NCSERVO" validate --format jsonl --fail-on never --config "$WORK/layout.toml" "$cap" \
        >"$WORK/configured.jsonl" || fail "$name: validate --config exit $?"
      cmp -s "$WORK/free.jsonl" "$WORK/configured.jsonl" ||
        fail "$name: findings differ: $(diff "$WORK/free.jsonl" "$WORK/configured.jsonl" | head -5)"
      for rule in SE-001 MSG-001; do
        grep -q "\"rule\":\"$rule\"" "$WORK/free.jsonl" || fail "$name: injected $rule not reported"
      done
      expected_source=startup
      [ "$startup" = cut ] && expected_source=inferred
      "$NCSERVO" validate --fail-on never "$cap" >"$WORK/free.txt"
      grep -q "^layout: $expected_source, $axes ax" "$WORK/free.txt" ||
        fail "$name: $(grep '^layout' "$WORK/free.txt"), expected $expected_source, $axes axes"
      if [ "$kind" = esl ]; then
        grep -q "^timestamps: probe" "$WORK/free.txt" || fail "$name: probe timestamps not used"
      fi
      if [ $((case_number % EVERY)) = 0 ]; then
        tshark_fields "$cap" "$WORK/free.tsv" -e _ws.expert.message
        tshark_fields "$cap" "$WORK/configured.tsv" -o "ncservo.config:$WORK/layout.toml" \
          -e _ws.expert.message
        cmp -s "$WORK/free.tsv" "$WORK/configured.tsv" ||
          fail "$name: tshark -2 differs: $(diff "$WORK/free.tsv" "$WORK/configured.tsv" | head -5)"
        grep -q "SE-001" "$WORK/free.tsv" || fail "$name: tshark shows no SE-001"
      fi
    done
  done
done
echo "inference_matrix: $case_number cases, no configuration reports what the exact one reports"
