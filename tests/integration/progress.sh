#!/usr/bin/env bash
# progress.sh SRC BUILD: a long `validate` on a terminal shows its progress on standard error
# (frames, rate, time), and nothing of it in a pipe or under CI (docs/cli.md#progress). The
# terminal is a pseudo-terminal from script(1); the run, 15 minutes at 1 kHz with 8 axes from the
# simulator on standard input, takes a few seconds.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program script
long="'$NCSERVO' simulate --scenario soak --axes 8 --duration 900 -o - 2>/dev/null | '$NCSERVO' validate -"
# tty SCREEN [ENV...]: the long run on a terminal, what the terminal showed in SCREEN.
tty() {
  local screen=$1
  shift
  env -u CI "$@" script -qec "$long" /dev/null >"$screen" 2>&1 ||
    fail "validate on a terminal exited $?: $(tail -3 "$screen")"
}
tty "$WORK/screen"
tr '\r' '\n' <"$WORK/screen" >"$WORK/lines"
grep -aq 'ncservo: standard input: [0-9]* frames, [0-9]* frames/s, [0-9]* s$' "$WORK/lines" ||
  fail "no progress line on the terminal: $(head -c 600 "$WORK/screen" | cat -v)"
grep -aq '^verdict: PASS' "$WORK/lines" || fail "no verdict: $(tail -c 300 "$WORK/screen" | cat -v)"
echo "ok a terminal: $(grep -ac 'frames/s' "$WORK/lines") progress lines, then the report"

tty "$WORK/ci" CI=1
! grep -aq 'frames/s' "$WORK/ci" || fail "progress under CI=1"
bash -c "$long" >"$WORK/out" 2>"$WORK/err" || fail "validate in a pipe exited $?"
! grep -q 'frames/s' "$WORK/err" "$WORK/out" || fail "progress in a pipe: $(head -3 "$WORK/err")"
echo "progress: on a terminal only; none under CI or in a pipe"
