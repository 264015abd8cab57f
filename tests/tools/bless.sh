#!/usr/bin/env bash
# bless.sh [BUILD]: regenerates the golden reports, captures/NAME.expected.json, from
# `ncservo validate --format json` on each bundled capture NAME.pcap or NAME.pcapng (normalised by
# golden.py: what tests bundled_capture and simulate_captures compare), then prints what changed
# (git diff --stat and the diff). A golden judges the rules, so it changes only in a commit that
# changes no rule (tests/README.md): with a rule changed and not committed, bless refuses. Commit
# the rule change and the tests that judge it first, then the goldens on their own, saying why.
# BUILD defaults to build/.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$src/build}
ncservo="$build/validator/ncservo"
[ -x "$ncservo" ] || { echo "bless: no $ncservo (build it first)" >&2; exit 2; }
cd "$src"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1 &&
  ! git diff --quiet HEAD -- validator/rules validator/incidents; then
  echo "bless: validator/rules or validator/incidents has uncommitted changes; commit them first," \
    "then bless the goldens in a commit that changes no rule (tests/README.md)" >&2
  exit 2
fi
trap 'rm -f captures/*.expected.json.report captures/*.expected.json.new' EXIT
goldens=(captures/*.expected.json)
[ -f "${goldens[0]}" ] || { echo "bless: no captures/*.expected.json" >&2; exit 2; }
for golden in "${goldens[@]}"; do
  stem=${golden%.expected.json}
  capture=""
  for candidate in "$stem.pcap" "$stem.pcapng"; do
    [ -f "$candidate" ] && capture=$candidate
  done
  [ -n "$capture" ] || { echo "bless: $golden has no capture $stem.pcap or $stem.pcapng" >&2; exit 2; }
  # The report is written whole before the golden is replaced: a failed run changes nothing.
  "$ncservo" validate --format json --fail-on never "$capture" >"$golden.report"
  python3 tests/tools/golden.py <"$golden.report" >"$golden.new"
  rm "$golden.report"
  mv "$golden.new" "$golden"
  echo "bless: $golden from $capture"
done
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  git --no-pager diff --stat -- "${goldens[@]}"
  git --no-pager diff -- "${goldens[@]}"
  if git diff --quiet -- "${goldens[@]}"; then echo "bless: no golden changed"; fi
else
  echo "bless: not a git checkout, so no diff to show"
fi
