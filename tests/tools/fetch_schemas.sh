#!/usr/bin/env bash
# fetch_schemas.sh DIR: puts the published schemas the CI formats are checked against into DIR
# (never into the repository), from npm packages that ship them:
#   DIR/jenkins-junit.xsd     the JUnit schema of Jenkins (junit-processor's copy of Jenkins'
#                             dtkit junit-4.xsd, MIT), the shape GitLab and Jenkins read
#   DIR/sarif-schema-2.1.0.json  SARIF 2.1.0 (Microsoft's jest-sarif ships the OASIS 2.1.0
#                             schema as sarif-2.1.0-rtm.5.json)
# Does nothing when both are there; exits 1 when they cannot be fetched (no npm, no registry).
set -euo pipefail
dir=$1
junit=junit-processor@0.0.6
sarif=@microsoft/jest-sarif@1.0.0-beta.0
[ -s "$dir/jenkins-junit.xsd" ] && [ -s "$dir/sarif-schema-2.1.0.json" ] && exit 0
command -v npm >/dev/null || { echo "fetch_schemas: npm not found" >&2; exit 1; }
mkdir -p "$dir"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent "$junit" "$sarif" >/dev/null)
tar -xzf "$tmp"/junit-processor-*.tgz -C "$tmp" package/schemas/jenkins-junit.xsd
mv "$tmp/package/schemas/jenkins-junit.xsd" "$dir/jenkins-junit.xsd"
tar -xzf "$tmp"/microsoft-jest-sarif-*.tgz -C "$tmp" package/lib/schemas/sarif-2.1.0-rtm.5.json
mv "$tmp/package/lib/schemas/sarif-2.1.0-rtm.5.json" "$dir/sarif-schema-2.1.0.json"
