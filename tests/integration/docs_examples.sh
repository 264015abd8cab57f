#!/usr/bin/env bash
# docs_examples.sh SRC BUILD: every shell example of README.md and docs/*.md runs and exits as the
# text says, so that no example can rot.
#
# The convention, for whoever writes an example:
# - A block fenced ```sh is a shell example and is run; other fences (```toml, ```text, plain
#   ```) are not.
# - Each block runs alone with `bash -e -o pipefail`, in an empty directory of its own that holds
#   `captures` (the repository's), `build` (the build tree, so `build/validator/ncservo` works)
#   and these files the examples may name: capture.pcap, capture.pcapng, a.pcapng, b.pcap (clean
#   simulated commissioning runs of 4 axes), layout.toml (their layout, as `simulate
#   --layout-config` writes it) and EtherCATConfig.xml (their ENI). HOME is that directory;
#   `ncservo` and `tshark` (with the plugin just built) are on PATH.
# - The block must exit 0, unless the line just before its fence says otherwise:
#   `<!-- exit: N -->` (the block's status, so such a block holds the one command that exits N).
# - `<!-- not tested: REASON -->` just before the fence skips a block that cannot run here (it
#   needs root, a sanitizer build, or hours); the reason is required. README's two commands,
#   `.ci/setup && .ci/demo` and `.ci/test`, are of this kind: they set up and run this very suite.
# - A ```text block just after `<!-- output: the end of the block above -->` is what the last
#   ```sh block before it prints last: its lines must be the last lines of that block's output.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

mkdir -p "$WORK/bin" "$WORK/fixtures" "$WORK/blocks"
ln -s "$NCSERVO" "$WORK/bin/ncservo"
# The wrapper runs the real tshark, found on the PATH without this directory.
printf '#!/bin/sh\nPATH="%s" exec "%s" "%s" "$@"\n' "$PATH" "$TSHARK" "$PLUGIN" >"$WORK/bin/tshark"
chmod 755 "$WORK/bin/tshark"
(
  cd "$WORK/fixtures"
  "$NCSERVO" simulate -o capture.pcapng --layout-config layout.toml --eni EtherCATConfig.xml
  "$NCSERVO" simulate -o capture.pcap
  cp capture.pcapng a.pcapng
  cp capture.pcap b.pcap
) 2>/dev/null

# One file per block: NNN.sh, and NNN.meta holding "FILE:LINE EXPECTED" or "FILE:LINE skip REASON".
python3 - "$SRC" "$WORK/blocks" <<'PY'
import pathlib, re, sys
src, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
docs = [src / "README.md"] + sorted((src / "docs").glob("*.md"))
n = 0
for doc in docs:
    lines = doc.read_text().split("\n")
    i = 0
    while i < len(lines):
        fence = re.match(r"^```(\S*)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        before = lines[i - 1].strip() if i > 0 else ""
        if before == "<!-- output: the end of the block above -->":
            if fence.group(1) != "text" or n == 0:
                sys.exit(f"{doc.relative_to(src)}:{i + 1}: an output mark needs a ```text block after a ```sh one")
            (out / f"{n - 1:03}.expect").write_text("\n".join(lines[i + 1:end]) + "\n")
        elif fence.group(1) == "sh":
            where = f"{doc.relative_to(src)}:{i + 1}"
            exit_mark = re.fullmatch(r"<!-- exit: (\d+) -->", before)
            skip_mark = re.fullmatch(r"<!-- not tested: (.+) -->", before)
            if before.startswith("<!--") and not (exit_mark or skip_mark):
                sys.exit(f"{where}: unknown mark before the block: {before}")
            meta = f"{where} skip {skip_mark.group(1)}" if skip_mark else \
                f"{where} {exit_mark.group(1) if exit_mark else 0}"
            (out / f"{n:03}.sh").write_text("\n".join(lines[i + 1:end]) + "\n")
            (out / f"{n:03}.meta").write_text(meta + "\n")
            n += 1
        i = end + 1
PY

ran=0 skipped=0
for block in "$WORK"/blocks/*.sh; do
  read -r where expected reason <"${block%.sh}.meta"
  if [ "$expected" = skip ]; then
    echo "skipped $where: $reason"
    skipped=$((skipped + 1))
    continue
  fi
  dir=$(mktemp -d "$WORK/run.XXXXXX")
  chmod 755 "$dir"
  cp "$WORK"/fixtures/* "$dir/"
  chmod a+r "$dir"/*
  ln -s "$SRC/captures" "$dir/captures"
  ln -s "$BUILD" "$dir/build"
  set +e
  (cd "$dir" && HOME="$dir" PATH="$WORK/bin:$PATH" timeout 300 bash -e -o pipefail "$block" \
    >"$dir/.stdout" 2>"$dir/.stderr")
  rc=$?
  set -e
  [ "$rc" = "$expected" ] ||
    fail "$where exited $rc, the text says $expected:
$(cat "$block")
stderr: $(tail -5 "$dir/.stderr")"
  expect=${block%.sh}.expect
  if [ -f "$expect" ]; then
    tail -n "$(wc -l <"$expect")" "$dir/.stdout" | diff -u "$expect" - >"$dir/.diff" ||
      fail "$where prints an end other than the text after it shows:
$(cat "$dir/.diff")"
  fi
  ran=$((ran + 1))
  rm -rf "$dir"
done
[ "$ran" -gt 0 ] || fail "no example found"
echo "docs_examples: $ran blocks ran as documented, $skipped not tested (their reasons above)"
