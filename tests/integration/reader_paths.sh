#!/usr/bin/env bash
# reader_paths.sh SRC BUILD
# The in-place capture reader against libpcap's (NCSERVO_CAPTURE_READER=libpcap, docs/benchmarks.md
# "Reading captures"): every report format of validate and decode's CSV, on every bundled, real and
# hostile capture, plain, from standard input, gzip and zstd, must be byte for byte the same, with
# the same exit status.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
[ -z "${NCSERVO_REAL_CAPTURES:-}" ] || REAL_CAPTURES=$NCSERVO_REAL_CAPTURES
require_program gzip zstd

captures=("$SRC"/captures/*.pcap "$SRC"/captures/*.pcapng)
if [ -d "$REAL_CAPTURES" ]; then
  for f in "$REAL_CAPTURES"/*; do
    case $f in *.pcap | *.pcapng | *.cap) captures+=("$f") ;; esac
  done
else
  [ -z "${CI:-}" ] || fail "no real captures at $REAL_CAPTURES"
  echo "note: no real captures at $REAL_CAPTURES"
fi
python3 "$GEN" --axes 2 --cycles 200 -o "$WORK/two-axes"
python3 "$GEN" --axes 2 --cycles 200 --format pcapng -o "$WORK/two-axes-ng"
python3 "$GEN" --axes 3 --cycles 200 --nanosecond -o "$WORK/nanosecond"
python3 "$SRC/tests/tools/hostile_captures.py" "$WORK/two-axes" "$WORK/hostile"
rm -f "$WORK/hostile/huge-sparse"  # 1 GiB of empty records: damaged_captures reads it
# Interfaces of different link types: libpcap refuses the second, the in-place reader reads both
# as Wireshark does (docs/cli.md#interfaces; damaged_captures and pcapng_interfaces read it).
rm -f "$WORK/hostile/pcapng-mixed-link-types"
captures+=("$WORK/two-axes-ng" "$WORK/nanosecond" "$WORK"/hostile/*)
# Cut in a record, in a record header, in a pcapng block; big-endian files (editcap keeps order,
# so the byte-swapped ones come from the generator's writer through Python).
size=$(stat -c %s "$WORK/two-axes-ng")
head -c $((size / 2 + 5)) "$WORK/two-axes-ng" >"$WORK/cut-ng"
head -c $((size - 3)) "$WORK/two-axes-ng" >"$WORK/cut-ng-tail"
size=$(stat -c %s "$WORK/two-axes")
head -c $((size / 3 + 3)) "$WORK/two-axes" >"$WORK/cut-pcap"
python3 - "$WORK/two-axes" "$WORK/big-endian.pcap" "$WORK/two-axes-ng" "$WORK/big-endian.pcapng" <<'PY'
import struct, sys
def pcap(src, dst):
    b = open(src, "rb").read()
    magic, vmaj, vmin, zone, sig, snap, link = struct.unpack("<IHHiIII", b[:24])
    out = [struct.pack(">IHHiIII", magic, vmaj, vmin, zone, sig, snap, link)]
    at = 24
    while at + 16 <= len(b):
        s, f, cap, orig = struct.unpack("<IIII", b[at:at + 16])
        out.append(struct.pack(">IIII", s, f, cap, orig) + b[at + 16:at + 16 + cap])
        at += 16 + cap
    open(dst, "wb").write(b"".join(out))
def pcapng(src, dst):
    b = open(src, "rb").read()
    out, at = [], 0
    while at + 12 <= len(b):
        kind, length = struct.unpack("<II", b[at:at + 8])
        body = b[at + 8:at + length - 4]
        if kind == 0x0A0D0D0A:
            magic, major, minor, section = struct.unpack("<IHHq", body[:16])
            body = struct.pack(">IHHq", magic, major, minor, section) + body[16:]
        elif kind == 1:
            link, _, snap = struct.unpack("<HHI", body[:8])
            opts, conv, i = body[8:], b"", 0
            while i + 4 <= len(opts):
                code, n = struct.unpack("<HH", opts[i:i + 4])
                value = opts[i + 4:i + 4 + (n + 3) // 4 * 4]
                if code == 14 and n == 8:
                    value = struct.pack(">q", struct.unpack("<q", value)[0])
                conv += struct.pack(">HH", code, n) + value
                i += 4 + (n + 3) // 4 * 4
                if code == 0:
                    break
            body = struct.pack(">HHI", link, 0, snap) + conv
        elif kind == 6:
            iface, hi, lo, cap, orig = struct.unpack("<IIIII", body[:20])
            body = struct.pack(">IIIII", iface, hi, lo, cap, orig) + body[20:]
        else:
            at += length
            continue
        out.append(struct.pack(">II", kind, length) + body + struct.pack(">I", length))
        at += length
    open(dst, "wb").write(b"".join(out))
pcap(sys.argv[1], sys.argv[2])
pcapng(sys.argv[3], sys.argv[4])
PY
captures+=("$WORK/cut-ng" "$WORK/cut-ng-tail" "$WORK/cut-pcap" "$WORK/big-endian.pcap" "$WORK/big-endian.pcapng")

# run OUT MODE COMMAND...: stdout, stderr and exit status of COMMAND in one file.
run() {
  local out=$1 mode=$2
  shift 2
  set +e
  if [ "$mode" = libpcap ]; then
    NCSERVO_CAPTURE_READER=libpcap "$@" >"$out" 2>"$out.err"
  else
    env -u NCSERVO_CAPTURE_READER "$@" >"$out" 2>"$out.err"
  fi
  echo "exit $?" >>"$out.err"
  set -e
}

# without_interfaces FILE FORMAT: FILE without what only the in-place reader can say of a pcapng of
# several interfaces, which libpcap reads as one (docs/cli.md#interfaces): the text's
# `interfaces:` line, JSON's `interfaces`.
without_interfaces() {
  case $2 in
    text) sed -i '/^interfaces: /d' "$1" ;;
    json) python3 - "$1" <<'PY' ;;
import json, sys
try:
    report = json.load(open(sys.argv[1]))
except ValueError:
    sys.exit(0)
for capture in report.get("captures", []):
    capture.pop("interfaces", None)
json.dump(report, open(sys.argv[1], "w"), indent=2)
PY
  esac
}

compared=0
for capture in "${captures[@]}"; do
  name=$(basename "$capture")
  several=false
  "$NCSERVO" validate --format json --fail-on never "$capture" >"$WORK/interfaces.json" 2>/dev/null || true
  if python3 -c '
import json, sys
captures = json.load(open(sys.argv[1]))["captures"]
sys.exit(0 if any(len(c.get("interfaces", [])) > 1 for c in captures) else 1)' "$WORK/interfaces.json"; then
    several=true
  fi
  gzip -c "$capture" >"$WORK/in.gz"
  zstd -q -c "$capture" >"$WORK/in.zst"
  for form in plain stdin gzip zstd; do
    case $form in
      plain) input=$capture ;;
      stdin) input=- ;;
      gzip) input=$WORK/in.gz ;;
      zstd) input=$WORK/in.zst ;;
    esac
    # Every report format for the plain file; the one JSON report for the others.
    formats=(json)
    [ $form != plain ] || formats=(text json jsonl junit sarif csv)
    for format in "${formats[@]}"; do
      for mode in inplace libpcap; do
        if [ $format = csv ]; then
          cmd=("$NCSERVO" decode --format csv "$input")
        else
          cmd=("$NCSERVO" validate --format "$format" "$input")
        fi
        if [ $form = stdin ]; then
          run "$WORK/$mode.out" $mode "${cmd[@]}" <"$capture"
          # and through a pipe, which cannot be mapped
          cat "$capture" | run "$WORK/$mode.pipe" $mode "${cmd[@]}"
        else
          run "$WORK/$mode.out" $mode "${cmd[@]}"
        fi
      done
      if $several; then
        for out in "$WORK"/{inplace,libpcap}.{out,pipe}; do [ ! -f "$out" ] || without_interfaces "$out" $format; done
      fi
      cmp -s "$WORK/inplace.out" "$WORK/libpcap.out" && cmp -s "$WORK/inplace.out.err" "$WORK/libpcap.out.err" ||
        fail "$name ($form, $format): the in-place reader differs from libpcap's:
$(diff "$WORK/libpcap.out" "$WORK/inplace.out" | head -8)
$(diff "$WORK/libpcap.out.err" "$WORK/inplace.out.err" | head -8)"
      if [ $form = stdin ]; then
        cmp -s "$WORK/inplace.pipe" "$WORK/libpcap.pipe" && cmp -s "$WORK/inplace.pipe.err" "$WORK/libpcap.pipe.err" ||
          fail "$name (pipe, $format): the in-place reader differs from libpcap's:
$(diff "$WORK/libpcap.pipe" "$WORK/inplace.pipe" | head -8)
$(diff "$WORK/libpcap.pipe.err" "$WORK/inplace.pipe.err" | head -8)"
      fi
      compared=$((compared + 1))
    done
  done
done
echo "reader_paths: ${#captures[@]} captures, $compared outputs byte-identical to libpcap's" \
  "(but a pcapng's interfaces of its own)"
