#!/usr/bin/env bash
# readme_pictures.sh SRC BUILD: the pictures of README.md and docs/*.md show what the tool prints
# today. docs/images/make.sh and make-wireshark.sh keep, beside each picture, the text it shows
# (docs/images/PICTURE.txt, written by docs/images/shown.sh when the picture is drawn); this makes
# that text again without drawing and compares, and checks that every rule ID and frame number the
# docs say of a picture (its alt text and the paragraphs either side) is in what it shows.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

pictures=(html-report.png gtkwave.png wireshark-finding.png drive-messages.png)
for picture in "${pictures[@]}"; do
  kept="$SRC/docs/images/${picture%.png}.txt"
  [ -s "$kept" ] || fail "no $kept: draw $picture with docs/images/make.sh or make-wireshark.sh"
  "$SRC/docs/images/shown.sh" "$picture" "$BUILD" >"$WORK/$picture.txt" ||
    fail "docs/images/shown.sh $picture exited $?"
  diff -u "$kept" "$WORK/$picture.txt" >"$WORK/$picture.diff" ||
    fail "$picture shows text the tool no longer prints; draw it again (docs/images/make.sh or make-wireshark.sh):
$(head -12 "$WORK/$picture.diff")"
done

python3 - "$SRC" "$WORK" "${pictures[@]}" <<'PY' || fail "the docs say of a picture what it does not show"
import pathlib, re, sys
src, work, pictures = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), sys.argv[3:]
ok, seen = True, set()
for doc in [src / "README.md"] + sorted((src / "docs").glob("*.md")):
    paragraphs = re.split(r"\n\s*\n", doc.read_text())
    for i, paragraph in enumerate(paragraphs):
        for alt, picture in re.findall(r"!\[([^\]]*)\]\((?:docs/)?images/([^)]+)\)", paragraph):
            if picture not in pictures:
                ok = False
                print(f"{doc.name}: {picture} is not one of the pictures shown.sh knows")
                continue
            seen.add(picture)
            shown = (work / f"{picture}.txt").read_text()
            said = " ".join(paragraphs[max(i - 1, 0):i + 2])
            for rule in sorted(set(re.findall(r"\b[A-Z]{2,4}-\d{3}\b", said))):
                if rule not in shown:
                    ok = False
                    print(f"{doc.name}: says {rule} of {picture}, which does not show it")
            for frame in sorted(set(re.findall(r"\bframe (\d+)", said))):
                if not re.search(rf"\bframe {frame}\b|^(?:list: |Frame ){frame}\t", shown, re.M):
                    ok = False
                    print(f"{doc.name}: says frame {frame} of {picture}, which does not show it")
missing = set(pictures) - seen
if missing:
    ok = False
    print(f"no doc shows {sorted(missing)}")
sys.exit(0 if ok else 1)
PY
echo "readme_pictures: ${pictures[*]} show today's output, and the docs say of them what they show"
