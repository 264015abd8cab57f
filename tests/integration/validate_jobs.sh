#!/usr/bin/env bash
# validate_jobs.sh SRC BUILD: `validate --jobs N` writes, for every report format (as
# `validate --help` lists them), with and without --verbose, to standard output and to --report
# files, the same bytes, the same messages on standard error and the same exit status as
# --jobs 1; over clean, faulty, cut, unreadable, no-servo captures and standard input.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

cd "$WORK"
captures=()
for i in 1 2 3 4 5 6; do
  "$NCSERVO" simulate --scenario faults --seed "$i" -o "f$i.pcap" 2>/dev/null
  "$NCSERVO" simulate --seed "$i" --duration 1 -o "c$i.pcapng" 2>/dev/null
  captures+=("f$i.pcap" "c$i.pcapng")
done
editcap -s 100 f1.pcap cut.pcap
echo "not a capture" >bad.pcap
head -c 30000 f2.pcap >short.pcap
captures+=(cut.pcap bad.pcap short.pcap "$SRC/captures/faults-4axis.pcap" \
           "$SRC/captures/sim-io-interleaved.pcapng" - c1.pcapng)

formats=$("$NCSERVO" validate --help | sed -n 's/.*--format TEXT:{\([^}]*\)}.*/\1/p' | tr , ' ')
[ -n "$formats" ] || fail "no formats in validate --help"
for format in $formats; do
  for verbose in "" --verbose; do
    for jobs in 1 2 5; do
      rc=0
      "$NCSERVO" validate --format "$format" $verbose --jobs "$jobs" --report "json:r$jobs.json" \
        --report "sarif:r$jobs.sarif" "${captures[@]}" <f3.pcap >"out.$jobs" 2>"err.$jobs" || rc=$?
      echo "$rc" >"rc.$jobs"
    done
    for jobs in 2 5; do
      for f in out err rc; do
        cmp -s "$f.1" "$f.$jobs" ||
          fail "$format $verbose --jobs $jobs: $f differs: $(diff "$f.1" "$f.$jobs" | head -5)"
      done
      cmp -s r1.json "r$jobs.json" || fail "$format $verbose --jobs $jobs: --report json differs"
      cmp -s r1.sarif "r$jobs.sarif" || fail "$format $verbose --jobs $jobs: --report sarif differs"
    done
    echo "ok $format $verbose (exit $(cat rc.1))"
  done
done
rc=0; "$NCSERVO" validate --jobs 0 f1.pcap 2>err || rc=$?
[ "$rc" = 2 ] || fail "--jobs 0: exit $rc"
echo PASS
