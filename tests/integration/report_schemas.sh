#!/usr/bin/env bash
# report_schemas.sh SRC BUILD: every kind of JUnit and SARIF report `validate` writes (findings,
# disabled rules, NO SERVO, a layout that does not fit, unreadable and compressed captures, several
# captures) is valid against the schema its readers use: Jenkins' JUnit XSD (xmllint) and the OASIS
# SARIF 2.1.0 JSON schema (python3-jsonschema; its formats too, as URIs, with python3-rfc3987).
# The schemas are fetched from npm packages into the
# build tree (tests/tools/fetch_schemas.sh, run by .ci/setup), never kept in the repository.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
schemas="$BUILD/schemas"
if ! "$SRC/tests/tools/fetch_schemas.sh" "$schemas" || ! command -v xmllint >/dev/null ||
  ! python3 -c "import jsonschema" 2>/dev/null; then
  skip "schemas (npm), xmllint or python3-jsonschema missing (.ci/setup installs them)"
fi

"$NCSERVO" simulate --scenario faults --axes 4 --seed 5 -o "$WORK/faults.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario faults --axes 4 --seed 3 -o "$WORK/nano.pcapng" 2>/dev/null
gzip -c "$WORK/nano.pcapng" >"$WORK/nano.pcapng.gz"
python3 "$GEN" --axes 2 --cycles 200 -o "$WORK/clean.pcap"
printf 'not a capture\n' >"$WORK/text.pcap"
printf '[[axis]]\nname = "ghost"\noutputs = 0x00090000\ninputs = 0x00090028\n' >"$WORK/ghost.toml"
# A layout whose first axis's inputs are two bytes early (docs/layout.md#a-layout-that-does-not-fit;
# not into another axis's inputs, which is a configuration error).
"$NCSERVO" simulate -o "$WORK/fit.pcap" --layout-config "$WORK/fit.toml" 2>/dev/null
python3 - "$WORK/fit.toml" "$WORK/misfit.toml" <<'PY'
import sys, tomllib
axes = tomllib.load(open(sys.argv[1], "rb"))["axis"]
with open(sys.argv[2], "w") as out:
    for i, a in enumerate(axes):
        out.write(f'[[axis]]\nname = "{a["name"]}"\noutputs = {a["outputs"]:#x}\n'
                  f'inputs = {a["inputs"] + (-2 if i == 0 else 0):#x}\n')
PY

cases=(  # NAME|ARGS (captures from $WORK)
  "findings|faults.pcap nano.pcapng nano.pcapng.gz"
  "disabled|faults.pcap --disable SE-001,COM-004 --fail-on warning"
  "clean|clean.pcap"
  "no_servo|clean.pcap --config ghost.toml"
  "misfit|fit.pcap --config misfit.toml"
  "misfit_failing|fit.pcap --config misfit.toml --fail-on warning"
  "unreadable|text.pcap missing.pcap faults.pcap"
)
n=0
for row in "${cases[@]}"; do
  name=${row%%|*}
  args=()
  for a in ${row#*|}; do [ -e "$WORK/$a" ] || [[ $a == missing* ]] && args+=("$WORK/$a") || args+=("$a"); done
  "$NCSERVO" validate --report junit:"$WORK/$name.xml" --report sarif:"$WORK/$name.sarif" "${args[@]}" \
    >/dev/null 2>&1 || true
  [ -s "$WORK/$name.xml" ] && [ -s "$WORK/$name.sarif" ] || fail "$name: no report"
  xmllint --noout --schema "$schemas/jenkins-junit.xsd" "$WORK/$name.xml" 2>"$WORK/xmllint.err" ||
    fail "$name: JUnit not valid: $(head -5 "$WORK/xmllint.err")"
  python3 - "$schemas/sarif-schema-2.1.0.json" "$WORK/$name.sarif" <<'PY' || fail "$name: SARIF not valid"
import json, sys, jsonschema
schema = json.load(open(sys.argv[1]))
cls = jsonschema.validators.validator_for(schema)
errors = sorted(cls(schema).iter_errors(json.load(open(sys.argv[2]))), key=lambda e: list(e.path))
for e in errors[:5]:
    print(list(e.path), e.message[:300], file=sys.stderr)
sys.exit(1 if errors else 0)
PY
  if [[ $name == misfit* ]]; then
    grep -q LAYOUT-FIT "$WORK/$name.sarif" && grep -q 'layout fits the data' "$WORK/$name.xml" ||
      fail "$name: no layout warning in SARIF or JUnit"
  fi
  n=$((n + 1))
done
# SARIF with its formats checked (uri, uri-reference: rfc3987, Debian's python3-rfc3987 for
# Debian's python3): captures named by a relative path holding a space and a non-ASCII letter, and
# by an absolute one, give percent-encoded URI references, the relative ones under a uriBaseId.
debian_python=/usr/bin/python3
"$debian_python" -c "import jsonschema, rfc3987" 2>/dev/null ||
  skip "Debian's python3-jsonschema or python3-rfc3987 missing (.ci/setup installs them)"
mkdir -p "$WORK/Prüfstand 1"
cp "$WORK/faults.pcap" "$WORK/Prüfstand 1/x.pcap"
(cd "$WORK" && "$NCSERVO" validate --format sarif -o formats.sarif "Prüfstand 1/x.pcap" \
  "$WORK/Prüfstand 1/x.pcap" text.pcap >/dev/null 2>&1) || [ $? = 3 ] || fail "validate exited $?"
"$debian_python" - "$schemas/sarif-schema-2.1.0.json" "$WORK/formats.sarif" "$WORK" <<'PY' ||
import json, sys, urllib.parse, jsonschema
schema, sarif, work = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3]
checker = jsonschema.FormatChecker()
# The check is real: the formats are known, and a raw path with a space fails it.
assert {"uri", "uri-reference"} <= set(checker.checkers), sorted(checker.checkers)
assert not checker.conforms("Prüfstand 1/x.pcap", "uri-reference")
cls = jsonschema.validators.validator_for(schema)
errors = sorted(cls(schema, format_checker=checker).iter_errors(sarif), key=lambda e: list(e.path))
for e in errors[:5]:
    print(list(e.path), e.message[:300], file=sys.stderr)
assert not errors
run = sarif["runs"][0]
locations = [a["location"] for a in run["artifacts"]]
assert locations[0] == {"uri": "Pr%C3%BCfstand%201/x.pcap", "uriBaseId": "SRCROOT"}, locations[0]
base = run["originalUriBaseIds"]["SRCROOT"]["uri"]
assert base.startswith("file:///") and base.endswith("/"), base
absolute = urllib.parse.unquote(urllib.parse.urlparse(base).path) + "Prüfstand 1/x.pcap"
assert urllib.parse.unquote(urllib.parse.urlparse(locations[1]["uri"]).path) == absolute, locations[1]
assert absolute == f"{work}/Prüfstand 1/x.pcap", absolute
assert locations[2] == {"uri": "text.pcap", "uriBaseId": "SRCROOT"}, locations[2]
for r in run["results"]:
    where = r["locations"][0]["physicalLocation"]["artifactLocation"]
    assert where["uri"] == locations[where["index"]]["uri"], r
PY
  fail "SARIF with a space and an umlaut in a path: not valid with its formats checked"
echo "report_schemas: $n runs' JUnit and SARIF valid against Jenkins' XSD and SARIF 2.1.0; URIs valid with formats checked"
