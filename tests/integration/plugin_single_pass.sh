#!/usr/bin/env bash
# plugin_single_pass.sh SRC BUILD
# Single-pass tshark (no -2), which shows each frame before the learning window has decided:
# - on an inferred-layout capture, exactly the window's frames (those -2 decodes but one pass
#   shows before the first frame it decodes) carry the chat note ncservo.layout_learning, with
#   its text, and the Info column says so; with -2 no frame does;
# - on a capture whose layout comes from its start-up, ESM-004 shows on frame 6 in one pass as
#   with -2, and no start-up frame carries the note;
# - every finding one pass shows is one -2 shows, with the same frame and text.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
inferred="$SRC/captures/faults-4axis.pcap"
startup="$SRC/captures/sim-faults-4axis.pcap"

run_tshark() { # OUT CAPTURE tshark-args...
  local out=$1 capture=$2
  shift 2
  "$TSHARK" "$PLUGIN" -r "$capture" "$@" >"$out" 2>"$WORK/tshark.err" ||
    fail "tshark -r $(basename "$capture") $* exited $?: $(cat "$WORK/tshark.err")"
  [ ! -s "$WORK/tshark.err" ] || fail "tshark $* printed on stderr: $(head -3 "$WORK/tshark.err")"
}

# A single pass holds the first cycles while the capture's clock is judged, then the learning
# window: both are noted, each with its own note.
held='ncservo.layout_learning or ncservo.clock_judging'
run_tshark "$WORK/noted1.txt" "$inferred" -Y "$held" -T fields -e frame.number
run_tshark "$WORK/decoded1.txt" "$inferred" -Y ncservo.axis -T fields -e frame.number
run_tshark "$WORK/decoded2.txt" "$inferred" -2 -Y ncservo.axis -T fields -e frame.number
run_tshark "$WORK/noted2.txt" "$inferred" -2 -Y "$held" -T fields -e frame.number
run_tshark "$WORK/tree1.txt" "$inferred" -c 2 -V -O ncservo
run_tshark "$WORK/list1.txt" "$inferred" -c 2
first=$(head -n1 "$WORK/decoded1.txt")
[ -n "$first" ] || fail "one pass decodes no frame of $(basename "$inferred")"
awk -v first="$first" '$1 < first' "$WORK/decoded2.txt" >"$WORK/window.txt"
[ -s "$WORK/window.txt" ] || fail "no learning window: one pass decodes from frame $first, as -2"
diff -u "$WORK/window.txt" "$WORK/noted1.txt" >"$WORK/noted.diff" ||
  fail "one pass: the noted frames are not the window's ($(wc -l <"$WORK/window.txt") frames" \
    "before frame $first): $(head -8 "$WORK/noted.diff")"
[ ! -s "$WORK/noted2.txt" ] || fail "-2 notes frames $(head -3 "$WORK/noted2.txt" | xargs)"
# The first frames are held while the clock is judged.
grep -qF 'Expert Info (Chat/Undecoded): capture'"'"'s clock being judged (docs/timing.md#the-clock): `tshark -2` or the GUI decodes this frame' \
  "$WORK/tree1.txt" || fail "-V on a window frame: no chat note: $(grep -m3 -i expert "$WORK/tree1.txt")"
grep -qF '[NCSERVO clock being judged]' "$WORK/list1.txt" ||
  fail "the Info column of a window frame: $(head -1 "$WORK/list1.txt")"

findings() { # OUT CAPTURE [-2]
  run_tshark "$1" "$2" ${3:+"$3"} -Y ncservo.finding -T fields -E occurrence=a -E aggregator='|' \
    -e frame.number -e ncservo.finding
}
for capture in "$inferred" "$startup"; do
  name=$(basename "$capture" .pcap)
  findings "$WORK/$name.1.tsv" "$capture"
  findings "$WORK/$name.2.tsv" "$capture" -2
  extra=$(comm -23 <(sort "$WORK/$name.1.tsv") <(sort "$WORK/$name.2.tsv"))
  [ -z "$extra" ] || fail "$name: one pass shows findings -2 does not: $(head -3 <<<"$extra")"
done
grep -qP '^6\tESM-004 al-error-at-init: ' "$WORK/sim-faults-4axis.1.tsv" ||
  fail "one pass: no ESM-004 on frame 6 of sim-faults-4axis.pcap: $(head -3 "$WORK/sim-faults-4axis.1.tsv")"
grep -qP '^6\tESM-004 al-error-at-init: ' "$WORK/sim-faults-4axis.2.tsv" ||
  fail "-2: no ESM-004 on frame 6 of sim-faults-4axis.pcap"
run_tshark "$WORK/startup-noted.txt" "$startup" -Y ncservo.layout_learning -T fields -e frame.number
[ ! -s "$WORK/startup-noted.txt" ] ||
  fail "a start-up frame of sim-faults-4axis.pcap carries the note: $(head -3 "$WORK/startup-noted.txt" | xargs)"
echo "plugin_single_pass: $(wc -l <"$WORK/noted1.txt") window frames noted before frame $first;" \
  "ESM-004 on frame 6 in one pass; $(wc -l <"$WORK/sim-faults-4axis.1.tsv") findings in one pass, all as -2"
