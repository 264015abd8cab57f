#!/usr/bin/env bash
# html_report.sh SRC BUILD: the HTML report of the faults capture in a real browser:
# loaded in headless Chromium from file:// with the network off, no console error, one table row
# per finding of the JSON report, each finding timeline drawing the rows its rule reads (as
# `ncservo rules --explain` lists them), no timeline for a rule that reads none (COM-005, on the
# simulated faults capture), no two labels of a timeline overlapping, and the finding's line drawn
# as docs/html-report.md describes it. Skipped (77) without Chromium and Selenium; under CI: fails.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
# Debian's python3, where python3-selenium is (another python3 may come first on the PATH).
debian_python=/usr/bin/python3
if ! [ -x /usr/bin/chromium ] || ! [ -x /usr/bin/chromedriver ] ||
  ! "$debian_python" -c "import selenium" 2>/dev/null; then
  skip "chromium, chromium-driver or python3-selenium missing (.ci/setup installs them)"
fi

capture="$SRC/captures/faults-4axis.pcap"
"$NCSERVO" validate --format html -o "$WORK/faults.html" --report json:"$WORK/faults.json" \
  "$capture" >/dev/null 2>&1 || [ $? = 1 ] || fail "validate exited $?"
[ -s "$WORK/faults.html" ] || fail "no HTML report"
grep -q '<script src=\|<link [^>]*href=\|https\?://[^"]*\.js' "$WORK/faults.html" &&
  fail "the report refers to something outside itself"

# Each rule's read rows, from the rule reference (`reads: scw.se, ssw.servo_en`).
"$NCSERVO" rules | awk '{print $1}' >"$WORK/rules.txt"
python3 - "$NCSERVO" "$WORK/rules.txt" "$WORK/reads.json" <<'PY'
import json, subprocess, sys
ncservo, rules, out = sys.argv[1:4]
reads = {}
for rule in open(rules).read().split():
    text = subprocess.run([ncservo, "rules", "--explain", rule], capture_output=True, text=True, check=True).stdout
    line = next(l for l in text.splitlines() if l.strip().startswith("reads:"))
    names = [n.strip() for n in line.split(":", 1)[1].split(",")]
    reads[rule] = ["ncservo." + n.replace(" (its class)", "") for n in names if n not in ("-", "al_state")]
json.dump(reads, open(out, "w"))
PY
# The line at the finding's frame, as the page's reader is told it looks.
marker=$(grep -oE 'The ([a-z]+ )?[a-z]+ line is the frame the finding was reported on' "$SRC/docs/html-report.md" |
  sed 's/^The //; s/ line is.*//')
[ -n "$marker" ] || fail "docs/html-report.md does not say how the finding's line is drawn"
"$debian_python" "$SRC/tests/tools/check_html_report.py" "$WORK/faults.html" "$WORK/faults.json" "$WORK/reads.json" "$marker" ||
  fail "the HTML report in Chromium"

# COM-005 reads no PDO bit: on the simulated faults capture (which has it) its findings get no
# timeline, and every other timeline still draws.
"$NCSERVO" validate --format html -o "$WORK/sim.html" --report json:"$WORK/sim.json" \
  "$SRC/captures/sim-faults-4axis.pcap" >/dev/null 2>&1 || [ $? = 1 ] || fail "validate exited $?"
grep -q '"rule": *"COM-005"' "$WORK/sim.json" || fail "captures/sim-faults-4axis.pcap has no COM-005"
"$debian_python" "$SRC/tests/tools/check_html_report.py" "$WORK/sim.html" "$WORK/sim.json" "$WORK/reads.json" "$marker" ||
  fail "the HTML report of the simulated faults capture in Chromium"

# What the drives and ESCs said (docs/drive-messages.md): the independent generator's SDO reads,
# aborts and a link fault, each a row of the page.
python3 "$SRC/tests/tools/gen_capture.py" --axes 4 --cycles 3000 --seed 5 --inject SE-001 --inject MBX-003 \
  --inject ERH-001 --incident link-fault -o "$WORK/mailbox.pcap" >/dev/null || fail "gen_capture.py exited $?"
"$NCSERVO" validate --format html -o "$WORK/mailbox.html" --report json:"$WORK/mailbox.json" \
  "$WORK/mailbox.pcap" >/dev/null 2>&1 || [ $? = 1 ] || fail "validate exited $?"
python3 -c 'import json, sys; c = json.load(open(sys.argv[1]))["captures"][0]; sys.exit(not (c["link_faults"] and c["drive_messages"]))' \
  "$WORK/mailbox.json" || fail "the generated capture has no link fault or no drive message"
"$debian_python" "$SRC/tests/tools/check_html_report.py" "$WORK/mailbox.html" "$WORK/mailbox.json" "$WORK/reads.json" "$marker" ||
  fail "the HTML report of drive messages and a link fault in Chromium"

# ... and the simulator's (--diagnosis): drives that report each fault, the NC's reads of 1003h,
# an abort and a bad cable.
"$NCSERVO" simulate --bad-link 0x3EB:0@1.2x3 --fault MBX-003@0.9:0 -o "$WORK/said.pcap" 2>/dev/null ||
  fail "simulate exited $?"
"$NCSERVO" validate --format html -o "$WORK/said.html" --report json:"$WORK/said.json" \
  "$WORK/said.pcap" >/dev/null 2>&1 || [ $? = 1 ] || fail "validate exited $?"
"$debian_python" "$SRC/tests/tools/check_html_report.py" "$WORK/said.html" "$WORK/said.json" "$WORK/reads.json" "$marker" ||
  fail "the HTML report of the simulated drives' messages and bad cable in Chromium"

# A report of several captures, one of them unreadable, also loads without a console error.
printf 'not a capture\n' >"$WORK/text.pcap"
"$NCSERVO" validate --format html -o "$WORK/two.html" --report json:"$WORK/two.json" \
  "$SRC/captures/commissioning-4axis.pcap" "$WORK/text.pcap" >/dev/null 2>&1 || true
"$debian_python" "$SRC/tests/tools/check_html_report.py" "$WORK/two.html" "$WORK/two.json" "$WORK/reads.json" ||
  fail "the HTML report of two captures in Chromium"
echo "html_report: ok"
