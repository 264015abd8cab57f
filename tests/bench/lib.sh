# Sourced by a benchmark right after `set -euo pipefail`, with the benchmark's arguments: -h or
# --help prints the benchmark's header comment; sets root (the repository), build (the first
# argument, default the repository's build/) and ncservo (the binary in it).
export LC_ALL=C  # decimal points in printf, awk, date and bc
if [ "${1:-}" = -h ] || [ "${1:-}" = --help ]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'
  exit 0
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
ncservo=$build/validator/ncservo
