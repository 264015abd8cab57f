#!/bin/sh
# man_page.sh NCSERVO OUT: ncservo.1 from the CLI's own help (help2man), each subcommand's
# --help as a section of its own, so the man page cannot drift from the program.
set -eu
ncservo=$1 out=$2
include=$(mktemp)
trap 'rm -f "$include"' EXIT
{
  echo "[COMMANDS]"
  for command in $("$ncservo" --help | sed -n '/^Subcommands:/,/^$/p' | awk 'NR > 1 && NF { print $1 }'); do
    echo ".SS ncservo $command"
    echo ".nf"
    "$ncservo" "$command" --help | sed "s|$ncservo|ncservo|g" | sed 's/\\/\\\\/g; s/^\./\\\&./'
    echo ".fi"
  done
  echo "[SEE ALSO]"
  echo "tshark(1), wireshark(1); /usr/share/doc/ncservo/ (README.md, docs/*.md)"
} >"$include"
help2man --no-info --no-discard-stderr --include "$include" \
  --name "decode and check NC <-> servo EtherCAT process data" "$ncservo" >"$out"
