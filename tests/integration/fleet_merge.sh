#!/usr/bin/env bash
# fleet_merge.sh SRC BUILD: docs/field.md's fleet recipe with the real GNU parallel (Debian's):
# a folder of recordings, one JSON report each through `parallel`, then `ncservo merge`; the merged
# counts (captures, verdicts, frames, cycles, lost cycles, wrong WKCs, findings by rule and
# severity, incidents by cause and kind, the timing series' counts, extremes and mean) are the
# per-capture reports' added up here; merging one report is that report; a file that is no
# report is named; an output that is an input is refused. Needs parallel: otherwise exit 77
# (under CI: fails).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program parallel

cd "$WORK"
mkdir -p recordings/line1 recordings/line2
cp "$SRC"/captures/*.pcap recordings/line1/
cp "$SRC"/captures/*.pcapng recordings/line2/
"$NCSERVO" simulate --scenario faults --cycle-us 2000 -o recordings/line2/faults-2ms.pcapng 2>/dev/null
export PATH="$BUILD/validator:$PATH"
# The recipe as docs/field.md gives it.
find recordings -name '*.pcap*' |
  parallel --will-cite -j2 'ncservo validate --format json --fail-on never -o {.}.json {}' ||
  fail "parallel exited $?"
reports=(recordings/*/*.json)
[ "${#reports[@]}" = "$(find recordings -name '*.pcap*' | wc -l)" ] || fail "not a report per capture: ${reports[*]}"
ncservo merge -o fleet.json "${reports[@]}" || fail "merge exited $?"
ncservo merge --format text "${reports[@]}" >fleet.txt || fail "merge --format text exited $?"

python3 - fleet.json "${reports[@]}" <<'PY' || fail "the merged counts are not the reports' sums"
import collections, json, math, sys
merged = json.load(open(sys.argv[1]))
captures = [c for path in sys.argv[2:] for c in json.load(open(path))["captures"]]
def same(what, got, want):
    assert got == want, f"{what}: merged {got}, the reports {want}"
same("reports", merged["reports"], sys.argv[2:])
same("captures", merged["captures"], len(captures))
same("verdicts", merged["verdicts"], dict(collections.Counter(c["verdict"] for c in captures)))
assert set(merged["verdicts"]) >= {"pass", "fail"}, merged["verdicts"]
for key in ("frames", "cycles"):
    same(key, merged[key], sum(c[key] for c in captures))
for key in ("lost_cycles", "wkc_errors"):
    same(key, merged[key], sum(c["timing"][key] for c in captures))
assert merged["lost_cycles"] > 0 and merged["wkc_errors"] > 0
findings = [f for c in captures for f in c["findings"]]
same("findings by rule", merged["findings"]["by_rule"], dict(collections.Counter(f["rule"] for f in findings)))
same("findings by severity", merged["findings"]["by_severity"],
     dict(collections.Counter(f["severity"] for f in findings)))
for c in captures:  # each report's own summary agrees with its findings
    for s in ("error", "warning", "info"):
        assert c["summary"][s] == sum(f["severity"] == s for f in c["findings"]), c["path"]
incidents = [i for c in captures for i in c["incidents"]]
assert incidents
same("incidents by cause", merged["incidents"]["by_cause"], dict(collections.Counter(i["cause"]["id"] for i in incidents)))
same("incidents by kind", merged["incidents"]["by_kind"], dict(collections.Counter(i["kind"] for i in incidents)))
for series in ("cycle_us", "latency_us"):
    parts = [c["timing"][series] for c in captures if c["timing"][series]]
    m = merged["timing"][series]
    n = sum(p["count"] for p in parts)
    same(series + " count", m["count"], n)
    same(series + " min", m["min"], min(p["min"] for p in parts))
    same(series + " max", m["max"], max(p["max"] for p in parts))
    mean = sum(p["mean"] * p["count"] for p in parts) / n
    assert abs(m["mean"] - mean) <= 0.001, (series, m["mean"], mean)
    var = sum((p["stddev"] ** 2 + p["mean"] ** 2) * p["count"] for p in parts) / n - mean ** 2
    assert abs(m["stddev"] - math.sqrt(max(var, 0))) <= 0.002, (series, m["stddev"], var)
    if m["histogram"] is not None:
        same(series + " histogram count", sum(b["count"] for b in m["histogram"]) + m["under"] + m["over"], n)
        # Each capture's bins, shifted by its zero, are among the merged ones.
        edges = {(b["from_us"], b["to_us"]) for b in m["histogram"]}
        for p in parts:
            for b in p["histogram"]:
                key = (round(p["histogram_zero"] + b["from_us"], 3), round(p["histogram_zero"] + b["to_us"], 3))
                assert key in edges, (series, key)
    else:
        assert m["histogram_not_merged"], m
print(f"ok merged {len(captures)} captures: {merged['verdicts']}, {len(findings)} findings, "
      f"{len(incidents)} incidents, {merged['timing']['cycle_us']['count']} cycle intervals")
PY
grep -q "^${#reports[@]} reports, " fleet.txt || fail "text: $(head -2 fleet.txt)"

# One report merged with itself: every count doubled, the bins line up, the median in the merged
# p50 bin.
one=recordings/line1/commissioning-4axis.json
ncservo merge "$one" "$one" >twice.json || fail "merge of one report twice"
python3 - "$one" twice.json <<'PY' || fail "one report merged twice"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]["timing"]["cycle_us"]
m = json.load(open(sys.argv[2]))["timing"]["cycle_us"]
assert m["count"] == 2 * c["count"] and m["min"] == c["min"] and m["max"] == c["max"], m
assert [b["count"] for b in m["histogram"]] == [2 * b["count"] for b in c["histogram"]], m
lo, hi = m["p50_bin"]
assert lo <= c["median"] < hi, (m["p50_bin"], c["median"])
print("ok one report twice: every count doubled, the median in its bin")
PY

# Errors name the file; nothing is written over an input.
echo 'not json' >bad.json
rc=0; ncservo merge "$one" bad.json 2>err || rc=$?
[ "$rc" = 3 ] && grep -q "bad.json: not JSON" err || fail "not JSON: exit $rc: $(cat err)"
echo '{"runs": []}' >other.json
rc=0; ncservo merge other.json 2>err || rc=$?
[ "$rc" = 3 ] && grep -q "other.json: not a JSON report of ncservo validate" err || fail "not a report: exit $rc: $(cat err)"
rc=0; ncservo merge "$one" nowhere.json 2>err || rc=$?
[ "$rc" = 3 ] && grep -q "nowhere.json: cannot read it" err || fail "missing: exit $rc: $(cat err)"
cp "$one" keep.json
rc=0; ncservo merge -o keep.json "$one" keep.json 2>err || rc=$?
[ "$rc" = 2 ] && grep -q "refusing to write over an input" err && cmp -s keep.json "$one" ||
  fail "output over an input: exit $rc: $(cat err)"
echo PASS
