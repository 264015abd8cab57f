#!/usr/bin/env bash
# interrupt.sh SRC BUILD: Ctrl-C (SIGINT) during `validate` of several captures
# (docs/cli.md#interrupted): the captures finished are reported (text on standard output, a JSON
# report file renamed into place whole), standard error says "interrupted at CAPTURE, frame N",
# and the exit status is 130. One capture at a time with the last one on standard input, cut
# while it waits for more, and with --jobs 2 on files, the last
# one long. Each with the capture read on the judging thread and on a thread of its own
# (--read-thread off and on: docs/cli.md#two-threads).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate --duration 1.5 -o "$WORK/a.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario faults -o "$WORK/b.pcap" 2>/dev/null
"$NCSERVO" simulate --duration 2 --seed 9 -o "$WORK/tail.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario soak --duration 120 -o "$WORK/long.pcap" 2>/dev/null
tail_frames=$("$NCSERVO" validate --format json "$WORK/tail.pcap" |
  python3 -c 'import json,sys; print(json.load(sys.stdin)["captures"][0]["frames"])')

for mode in off on; do
python3 - "$NCSERVO" "$WORK" "$tail_frames" "$mode" <<'PY' || fail "--read-thread $mode: Ctrl-C while validate reads its last capture"
import json, os, signal, subprocess, sys, time
ncservo, work, tail_frames, mode = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
if os.path.exists(f"{work}/r.json"):
    os.remove(f"{work}/r.json")
# A shell running this in the background ignores SIGINT, and a child keeps it ignored.
default_sigint = lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)

def interrupted(argv, stdin, ready):
    p = subprocess.Popen([ncservo, "validate", "--read-thread", mode, "--fail-on", "never", *argv], stdin=stdin,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=work,
                         preexec_fn=default_sigint)
    deadline = time.time() + 60
    while not ready(p.pid):
        assert p.poll() is None, f"validate ended before Ctrl-C: {p.returncode} {p.stderr.read()}"
        assert time.time() < deadline, "validate never reached its last capture"
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    return p.returncode, out.decode(), err.decode()

started = time.time()
def waits_on_pipe(pid):  # every byte of standard input read, waiting for more
    try:
        wchan = open(f"/proc/{pid}/wchan").read()
    except OSError:
        return False
    if wchan in ("", "0"):  # a kernel that hides it: the tail capture is read well within 5 s
        return time.time() - started > 5
    return "pipe" in wchan

def check(rc, out, err, finished, cut, json_path):
    assert rc == 130, (rc, err)
    lines = [l for l in err.splitlines() if "interrupted at" in l]
    assert [l.split("interrupted at ")[1].rsplit(", frame ", 1)[0] for l in lines] == cut, err
    report = json.load(open(json_path))
    assert [c["path"] for c in report["captures"]] == finished, report["captures"]
    assert not [f for f in os.listdir(work) if f.startswith(".r.json")], "temporary left"
    verdicts = [l for l in out.splitlines() if l.startswith("capture verdict:")]
    assert len(verdicts) == len(finished), out
    last = out.splitlines()[-1]
    assert last.startswith("verdict: INTERRUPTED - ") and "(exit 130: " in last, last
    assert "PASS" not in last, last
    return lines

# One capture at a time: the last is standard input that stays open after the tail capture.
feeder = subprocess.Popen(["sh", "-c", f"cat {work}/tail.pcap; exec sleep 120"],
                          stdout=subprocess.PIPE)
try:
    rc, out, err = interrupted(["--jobs", "1", "--report", "json:r.json", "a.pcap", "b.pcap", "-"],
                               feeder.stdout, waits_on_pipe)
finally:
    feeder.kill()
lines = check(rc, out, err, ["a.pcap", "b.pcap"], ["standard input"], f"{work}/r.json")
# Where it stopped: a frame of the tail capture (the last few may still wait in a buffer).
frame = int(lines[0].rsplit(", frame ", 1)[1])
assert 0 < frame <= tail_frames, lines
assert "capture verdict: FAIL" in out, out  # b.pcap's own verdict: errors, whatever --fail-on

# Two at a time, the long capture last: interrupted as soon as it is open.
def reads_long(pid):
    try:
        return any(os.readlink(f"/proc/{pid}/fd/{fd}").endswith("/long.pcap")
                   for fd in os.listdir(f"/proc/{pid}/fd"))
    except OSError:
        return False

os.remove(f"{work}/r.json")
rc, out, err = interrupted(["--jobs", "2", "--report", "json:r.json", "a.pcap", "b.pcap",
                            "long.pcap"], subprocess.DEVNULL, reads_long)
cut = [l.split("interrupted at ")[1].rsplit(", frame ", 1)[0]
       for l in err.splitlines() if "interrupted at" in l]
assert "long.pcap" in cut, err
unstarted = [n for l in err.splitlines() if "interrupted before " in l
             for n in l.split("interrupted before ")[1].split(", ")]
finished = [c for c in ["a.pcap", "b.pcap", "long.pcap"] if c not in cut + unstarted]
check(rc, out, err, finished, cut, f"{work}/r.json")
PY
done
echo "interrupt: Ctrl-C writes the captures finished, says where it stopped, exits 130"
