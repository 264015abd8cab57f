#!/usr/bin/env bash
# outputs_in_repo.sh SRC BUILD: nothing ncservo prints points outside the repository:
# the --help of every command, the listings, every rule's explanation, the reports in
# every format and the error messages name docs/*.md, never the design documents the repository
# does not hold.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
outside='RULES\.md|PROTOCOL\.md|INTERFACES\.md|STYLE\.md|\.\./shared|seed 0[0-9]'
all="$WORK/all.txt"
: >"$all"
say() {  # say ARGS...: ncservo's stdout and stderr, whatever its exit status, go to all.txt
  { echo "### ncservo $*"; "$NCSERVO" "$@" 2>&1 || true; } >>"$all"
}

say --help
for command in decode validate rules fields simulate; do say "$command" --help; done
say rules
say rules --format markdown
say fields
say fields --format markdown
for id in $("$NCSERVO" rules | awk '{print $1}'); do say rules --explain "$id"; done
say simulate --list-faults
"$NCSERVO" simulate --axes 2 --duration 1 --no-startup -o "$WORK/no-startup.pcap" 2>/dev/null
for capture in "$SRC/captures/faults-4axis.pcap" "$SRC/captures/sim-io-interleaved.pcapng"; do
  for format in text json jsonl junit sarif html; do say validate --format "$format" "$capture"; done
  say decode --layout "$capture"
done
say validate --no-default-layout "$WORK/no-startup.pcap"
say decode --no-default-layout "$WORK/no-startup.pcap"
printf 'bogus = 1\n[[axis]]\noutputs = 0\n' >"$WORK/bad.toml"
say validate --config "$WORK/bad.toml" "$WORK/no-startup.pcap"
say validate --disable XX-1 --timeout x=1 "$WORK/no-startup.pcap"
say valdate
say validate --formt json x
say simulate --fault SE-003@2.9 -o "$WORK/x.pcap"
say validate "$WORK/missing.pcap"
[ "$(grep -c '^### ' "$all")" -gt 50 ] || fail "too few outputs collected"
if grep -nE "$outside" "$all" >"$WORK/hits"; then
  fail "ncservo points outside the repository: $(head -5 "$WORK/hits")"
fi
grep -q "docs/" "$all" || fail "no output points into docs/"
echo "outputs_in_repo: $(grep -c '^### ' "$all") outputs, none pointing outside the repository"
