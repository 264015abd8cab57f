#!/usr/bin/env bash
# docs_generated.sh SRC BUILD: docs/rules.md and docs/fields.md hold exactly the tables
# `ncservo rules --format markdown` and `ncservo fields --format markdown` print (the rules and
# their timeouts, the fields; no drift: regenerate them with those commands when a table changes).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
for doc in rules fields; do
  "$NCSERVO" "$doc" --format markdown | grep '^|' >"$WORK/$doc.md"
  grep '^|' "$SRC/docs/$doc.md" >"$WORK/$doc.doc" || true
  diff -u "$WORK/$doc.doc" "$WORK/$doc.md" >"$WORK/$doc.diff" ||
    fail "docs/$doc.md differs from \`ncservo $doc --format markdown\`: $(head -8 "$WORK/$doc.diff")"
done
# docs/configuration.md explains each timeout and limit in words: every one of the tables has its
# row (the limits' rows start the same way).
for timeout in $(grep -o '^| `[a-z_]*` | [0-9]* |' "$WORK/rules.md" | cut -d'`' -f2); do
  grep -q "^| \`$timeout\` |" "$SRC/docs/configuration.md" ||
    fail "docs/configuration.md has no row for the timeout or limit $timeout"
done
echo "docs_generated: docs/rules.md and docs/fields.md match the tables; configuration.md names every timeout and limit"
