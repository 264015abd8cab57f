#!/usr/bin/env bash
# monitor_metrics.sh SRC BUILD: `ncservo monitor --metrics` scraped by a real Prometheus server
# (Debian's prometheus, started here with its own configuration and storage on free ports) while
# tcpreplay replays a simulated capture with faults into a veth pair in a network namespace. Once
# the replay is over, PromQL queries through Prometheus' HTTP API give the same counts as
# `ncservo validate --format json` of the frames the monitor captured (its flight recording,
# spanning the run): frames, findings by rule and axis, incidents by cause, lost cycles, WKC
# errors, the timing series' counts, each axis's state and telegram failures, the clock. The
# exposition passes `promtool check metrics`. Needs root (veth, namespaces), tcpreplay and
# prometheus: otherwise exit 77 with the reason (under CI: fails).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (veth pair, network namespace)"
require_program tcpreplay ip prometheus promtool curl

veth_pair ncsp
cd "$WORK"
"$NCSERVO" simulate --scenario faults --cycle-us 4000 -o faults.pcap 2>/dev/null

metrics_port=$(free_port)
rm -rf rec && mkdir rec
"$NCSERVO" monitor -i "$host" --format jsonl --metrics "127.0.0.1:$metrics_port" \
  --record rec --record-window 60 >live.jsonl 2>live.err &
monitor=$!
prom_port=$(free_port)
cat >prometheus.yml <<YML
global:
  scrape_interval: 500ms
  scrape_timeout: 400ms
scrape_configs:
  - job_name: ncservo
    static_configs:
      - targets: ['127.0.0.1:$metrics_port']
        labels: {machine: 'test-cell'}
YML
prometheus --config.file=prometheus.yml --storage.tsdb.path=tsdb \
  --web.listen-address="127.0.0.1:$prom_port" >prometheus.log 2>&1 &
prom=$!
trap 'kill "$prom" "$monitor" 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$WORK"' EXIT
api="http://127.0.0.1:$prom_port/api/v1"

# query PROMQL: the result vector as JSON.
query() {
  curl -sf --get "$api/query" --data-urlencode "query=$1" || fail "PromQL $1: no answer"
}
target_up() { query 'up{job="ncservo"} == 1' | grep -q '"value"'; }
wait_for 150 curl -sf "http://127.0.0.1:$prom_port/-/ready" || fail "prometheus not ready: $(tail -5 prometheus.log)"
wait_for 150 target_up || fail "prometheus never scraped the monitor: $(cat live.err)"
echo "ok prometheus scrapes the monitor"

replay_into_peer faults.pcap
# The monitor hands its snapshot over every 100 ms; three scrapes after the replay hold the end.
sleep 2
curl -sf "http://127.0.0.1:$metrics_port/metrics" >scrape.txt || fail "no /metrics"
promtool check metrics <scrape.txt >promtool.out 2>&1 || fail "promtool check metrics: $(cat promtool.out)"
[ ! -s promtool.out ] || fail "promtool check metrics says: $(cat promtool.out)"
echo "ok promtool check metrics: clean ($(grep -c '^ncservo_' scrape.txt) series)"

for q in 'ncservo_frames_total' 'sum by (rule, axis) (ncservo_findings_total)' \
  'sum by (cause) (ncservo_incidents_total)' 'ncservo_lost_cycles_total' 'ncservo_wkc_errors_total' \
  'ncservo_cycle_seconds_count' 'ncservo_return_latency_seconds_count' 'ncservo_axis_state == 1' \
  'ncservo_telegram_failures' 'ncservo_clock_source == 1' \
  'ncservo_axis_state{state=~"error|fault reaction active"} == 1' \
  'sum by (machine) (increase(ncservo_lost_cycles_total[1h]))'; do
  printf '%s\t%s\n' "$q" "$(query "$q")"
done >promql.tsv

# The dashboard's queries are PromQL Prometheus accepts, over names the monitor serves.
python3 - "$SRC/docs/grafana/ncservo-dashboard.json" scrape.txt "$api" <<'PY' || fail "docs/grafana/ncservo-dashboard.json"
import json, re, sys, urllib.parse, urllib.request
dashboard, scrape, api = sys.argv[1:]
served = {line.split()[2] for line in open(scrape) if line.startswith("# TYPE ")}
exprs = [t["expr"] for p in json.load(open(dashboard))["panels"] for t in p["targets"]]
assert len(exprs) >= 10, exprs
for expr in exprs:
    for name in re.findall(r"\bncservo_[a-z_]+", expr):
        family = re.sub(r"_(bucket|count|sum)$", "", name)
        assert family in served, f"{expr}: {name} is not served"
    q = (expr.replace("$instance", ".*").replace("$__range", "1h").replace("$__rate_interval", "1m"))
    answer = json.load(urllib.request.urlopen(api + "/query?" + urllib.parse.urlencode({"query": q})))
    assert answer["status"] == "success", (expr, answer)
print(f"ok the dashboard's {len(exprs)} queries run against Prometheus over served names")
PY

kill -INT "$monitor"
rc=0
wait "$monitor" || rc=$?
[ "$rc" = 1 ] || fail "monitor: exit $rc (findings of errors: 1): $(cat live.err)"
grep -q "frames captured; dropped: 0 by the kernel" live.err || fail "the capture dropped frames: $(cat live.err)"
grep -q -- "--metrics: [1-9][0-9]* scrapes" live.err || fail "no scrape counted: $(cat live.err)"
recordings=(rec/*.pcapng)
[ "${#recordings[@]}" = 1 ] || fail "a 60 s window over the run: ${#recordings[@]} recordings"
"$NCSERVO" validate --format json --fail-on never "${recordings[0]}" >rec.json

python3 - promql.tsv rec.json <<'PY' || fail "Prometheus' counts differ from validate's"
import collections, json, sys
answers = {}
for line in open(sys.argv[1]):
    q, j = line.rstrip("\n").split("\t")
    answers[q] = json.loads(j)["data"]["result"]
capture = json.load(open(sys.argv[2]))["captures"][0]
def scalar(q):
    r = answers[q]
    assert len(r) == 1, f"{q}: {r}"
    return float(r[0]["value"][1])
def by(q, label):
    return {tuple(s["metric"].get(l, "") for l in label): float(s["value"][1]) for s in answers[q]}
checks = 0
def same(what, prom, report):
    global checks
    checks += 1
    assert prom == report, f"{what}: Prometheus {prom}, validate {report}"
same("frames", scalar("ncservo_frames_total"), capture["frames"])
names = {a["index"]: a["name"] for a in capture["layout"]["axes"]}
want = collections.Counter((f["rule"], f["axis_name"] or "") for f in capture["findings"])
got = {k: v for k, v in by("sum by (rule, axis) (ncservo_findings_total)", ("rule", "axis")).items() if v}
same("findings by rule and axis", got, {k: float(v) for k, v in want.items()})
assert sum(want.values()) > 5, "the faults capture has findings"
want = collections.Counter(i["cause"]["id"] for i in capture["incidents"])
got = {k[0]: v for k, v in by("sum by (cause) (ncservo_incidents_total)", ("cause",)).items() if v}
same("incidents by cause", got, {k: float(v) for k, v in want.items()})
t = capture["timing"]
same("lost cycles", scalar("ncservo_lost_cycles_total"), t["lost_cycles"])
same("wkc errors", scalar("ncservo_wkc_errors_total"), t["wkc_errors"])
same("cycles", scalar("ncservo_cycle_seconds_count"), t["cycle_us"]["count"])
same("latencies", scalar("ncservo_return_latency_seconds_count"), (t["latency_us"] or {"count": 0})["count"])
same("axis states", {k[0]: k[1] for k in by("ncservo_axis_state == 1", ("axis", "state"))},
     {a["name"]: a["state"] for a in capture["axes"]})
same("telegram failures", by("ncservo_telegram_failures", ("axis",)),
     {(a["name"],): float(a["telegram_failures"]) for a in capture["axes"]})
same("clock", list(by("ncservo_clock_source == 1", ("source",))), [(capture["clock"]["source"],)])
faulted = sorted(a["name"] for a in capture["axes"] if a["state"] in ("error", "fault reaction active"))
same("axes in fault now", sorted(k[0] for k in by('ncservo_axis_state{state=~"error|fault reaction active"} == 1', ("axis",))), faulted)
per_hour = by("sum by (machine) (increase(ncservo_lost_cycles_total[1h]))", ("machine",))
assert list(per_hour) == [("test-cell",)], per_hour
# increase() extrapolates to the window's edges: at least the count, never less.
assert per_hour[("test-cell",)] >= t["lost_cycles"] > 0, (per_hour, t["lost_cycles"])
print(f"ok {checks} PromQL answers = validate's counts of the recording "
      f"({int(scalar('ncservo_frames_total'))} frames, {len(capture['findings'])} findings, "
      f"{len(capture['incidents'])} incidents, {t['lost_cycles']} lost cycles)")
PY

# The ESC counters' rises (docs/drive-messages.md): the generator's lost link and bad cable, per
# slave, port and counter, as validate of the monitor's recording lists them.
python3 "$SRC/tests/tools/gen_capture.py" --axes 3 --cycles 3000 --seed 5 --inject LNK-002 \
  --incident link-fault -o links.pcap >/dev/null || fail "gen_capture.py exited $?"
esc_port=$(free_port)
rm -rf esc-rec && mkdir esc-rec
"$NCSERVO" monitor -i "$host" --metrics "127.0.0.1:$esc_port" --record esc-rec --record-window 60 \
  >/dev/null 2>esc.err &
monitor=$!
wait_for 50 curl -sf "http://127.0.0.1:$esc_port/metrics" -o /dev/null || fail "no /metrics: $(cat esc.err)"
replay_into_peer links.pcap || fail "tcpreplay failed"
sleep 1
curl -sf "http://127.0.0.1:$esc_port/metrics" >esc-scrape.txt || fail "no /metrics"
kill -INT "$monitor"
wait "$monitor" || true
esc_recordings=(esc-rec/*.pcapng)
"$NCSERVO" validate --format json --fail-on never "${esc_recordings[0]}" >esc.json
python3 - esc-scrape.txt esc.json <<'PY' || fail "ncservo_esc_errors_total"
import collections, json, re, sys
scrape, report = sys.argv[1:]
got = {}
for line in open(scrape):
    m = re.match(r'ncservo_esc_errors_total\{station="(0x[0-9A-F]+)",port="(\d+)",counter="([a-z-]+)"\} (\S+)', line)
    if m:
        got[(m[1], int(m[2]), m[3])] = float(m[4])
want = collections.Counter()
for e in json.load(open(report))["captures"][0]["esc_errors"]:
    if e["station"] is not None:
        want[(f"0x{e['station']:04X}", e["port"], e["counter"])] += e["delta"]
assert want, "the capture was to hold counter rises"
assert got == {k: float(v) for k, v in want.items()}, f"scraped {got}, validate of the recording {dict(want)}"
print(f"ok ncservo_esc_errors_total: {len(got)} series = validate's esc_errors of the recording")
PY
echo PASS
