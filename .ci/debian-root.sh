#!/usr/bin/env bash
# Fresh Debian roots for CI: the test suite on other releases (.ci/run) and the package install test.
#
#   .ci/debian-root.sh create RELEASE ROOT   a fresh ROOT of RELEASE (bookworm, trixie, sid), mounted
#   .ci/debian-root.sh run ROOT COMMAND...   COMMAND as root inside ROOT
#   .ci/debian-root.sh remove ROOT           unmounts and deletes ROOT
#   .ci/debian-root.sh base RELEASE          makes the cached base of RELEASE if it has none
#   .ci/debian-root.sh has-base RELEASE      whether the cache has a base of RELEASE
#   .ci/debian-root.sh purge                 deletes the cache
#   .ci/debian-root.sh mirror                prints the Debian archive the roots come from
#
# Cached between runs on the same machine: the debootstrapped base of each release as a tarball, and
# the .deb files apt fetched into roots of that release (under NCSERVO_ROOT_CACHE, default
# /var/cache/ncservo-roots). The live root is always unpacked fresh and removed when the run is over,
# so nothing one run installs leaks into the next. A base older than NCSERVO_ROOT_MAX_AGE_DAYS
# (default 7) is made anew, so the roots follow the archive.
set -euo pipefail

cache=${NCSERVO_ROOT_CACHE:-/var/cache/ncservo-roots}
max_age_days=${NCSERVO_ROOT_MAX_AGE_DAYS:-7}
node_extra_ca=/etc/ncservo-node-extra-ca.crt  # in the root

die() {
  echo "debian-root.sh: $*" >&2
  exit 1
}

# The Debian archive this machine's own apt uses: the first source of its deb822 files
# (/etc/apt/sources.list.d/*.sources) or, without one, of /etc/apt/sources.list, that is not the
# security archive. NCSERVO_DEBIAN_MIRROR names another; NCSERVO_APT_ETC reads another /etc/apt
# (the test debian_root_mirror).
apt_etc=${NCSERVO_APT_ETC:-/etc/apt}
apt_mirror() {
  local found="" f
  for f in "$apt_etc"/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    found=$(awk '
      function stanza() { if (uris != "" && types ~ /(^| )deb( |$)/ && uris !~ /security/) { split(uris, u, " "); print u[1]; done = 1; exit } uris = ""; types = "" }
      /^[ \t]*$/ { stanza(); next }
      /^URIs:/ { sub(/^URIs:[ \t]*/, ""); uris = $0 }
      /^Types:/ { sub(/^Types:[ \t]*/, ""); types = $0 }
      END { if (!done) stanza() }' "$f")
    [ -z "$found" ] || break
  done
  if [ -z "$found" ] && [ -f "$apt_etc/sources.list" ]; then
    found=$(awk '$1 == "deb" { i = 2; if ($2 ~ /^\[/) while (i <= NF && $i !~ /\]$/) i++; if ($2 ~ /^\[/) i++; if ($i !~ /security/) { print $i; exit } }' "$apt_etc/sources.list")
  fi
  echo "${found%/}"
}
mirror=${NCSERVO_DEBIAN_MIRROR:-$(apt_mirror)}
[ -n "$mirror" ] || [ "${1:-}" = purge ] || [ "${1:-}" = mirror ] || [ "${1:-}" = remove ] || [ "${1:-}" = run ] ||
  die "no Debian archive in this machine's apt sources (/etc/apt/sources.list.d/*.sources, /etc/apt/sources.list); name one with NCSERVO_DEBIAN_MIRROR"

has_base() {
  local tarball="$cache/$1-base.tar"
  [ -f "$tarball" ] && [ -z "$(find "$tarball" -mtime "+$max_age_days")" ]
}

base_tarball() {
  local release=$1 tarball="$cache/$1-base.tar"
  if has_base "$release"; then
    echo "$tarball"
    return
  fi
  command -v debootstrap >/dev/null || die "debootstrap not installed (.ci/setup)"
  mkdir -p "$cache"
  local staging="$cache/$release.partial"
  rm -rf "$staging"
  echo "debian-root.sh: debootstrap $release from $mirror (minutes)" >&2
  # sid's Release file in a snapshot archive is past its Valid-Until date; debootstrap itself does
  # not check it, apt inside the root does (configured in create).
  if ! debootstrap --variant=minbase "$release" "$staging" "$mirror" >"$cache/$release.log" 2>&1; then
    rm -rf "$staging"
    die "debootstrap $release failed: $(tail -3 "$cache/$release.log")"
  fi
  rm -rf "$staging/var/cache/apt/archives/"*.deb
  tar -C "$staging" -cf "$tarball.new" . && mv "$tarball.new" "$tarball"
  rm -rf "$staging"
  echo "$tarball"
}

mount_all() {
  local root=$1 release=$2
  # A bind mount of the root onto itself makes it a mount point, which `ip netns` needs in a chroot.
  mount --bind "$root" "$root"
  mount -t proc proc "$root/proc"
  mount -t sysfs sysfs "$root/sys"
  mount --bind /dev "$root/dev"
  mount -t devpts devpts "$root/dev/pts" -o newinstance,ptmxmode=0666 2>/dev/null || true
  mount -t tmpfs tmpfs "$root/dev/shm"
  mount -t tmpfs tmpfs "$root/run"
  mkdir -p "$cache/$release-debs" "$root/var/cache/apt/archives"
  mount --bind "$cache/$release-debs" "$root/var/cache/apt/archives"
  # The cache itself, so that a test inside the root (the package install) makes its own root
  # from the same bases.
  mkdir -p "$root$cache"
  mount --bind "$cache" "$root$cache"
}

create() {
  local release=$1 root=$2
  [ ! -e "$root" ] || die "$root exists; remove it first"
  local tarball
  tarball=$(base_tarball "$release")
  mkdir -p "$root"
  tar -C "$root" -xf "$tarball"
  echo "$release" >"$root/.ncservo-release"
  cp /etc/resolv.conf "$root/etc/resolv.conf"
  printf '127.0.0.1 localhost\n::1 localhost ip6-localhost ip6-loopback\n' >"$root/etc/hosts"
  echo "deb $mirror $release main" >"$root/etc/apt/sources.list"
  # The archive here is a snapshot: sid's Release file is past its Valid-Until date.
  echo 'Acquire::Check-Valid-Until "false";' >"$root/etc/apt/apt.conf.d/99ncservo-snapshot"
  # Keep what apt fetches (the archives folder is the shared cache).
  echo 'APT::Keep-Downloaded-Packages "true";' >>"$root/etc/apt/apt.conf.d/99ncservo-snapshot"
  rm -f "$root/etc/apt/apt.conf.d/docker-clean"
  # A machine whose HTTPS goes through a proxy with its own certificate authority names it to
  # Node.js (npm fetches the report schemas): the root gets the same file, at a path of its own,
  # since the root's ca-certificates package rewrites its own bundle without that authority.
  if [ -n "${NODE_EXTRA_CA_CERTS:-}" ] && [ -f "$NODE_EXTRA_CA_CERTS" ]; then
    cp "$NODE_EXTRA_CA_CERTS" "$root$node_extra_ca"
  fi
  mount_all "$root" "$release"
}

run() {
  local root=$1
  shift
  [ -f "$root/.ncservo-release" ] || die "$root is not a root made by debian-root.sh"
  local extra_ca=""
  [ -f "$root$node_extra_ca" ] && extra_ca=$node_extra_ca
  chroot "$root" env -i HOME=/root LANG=C.UTF-8 TERM=dumb DEBIAN_FRONTEND=noninteractive \
    PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin CI="${CI:-}" \
    ${extra_ca:+NODE_EXTRA_CA_CERTS="$extra_ca"} "$@"
}

remove() {
  local root=$1
  [ -e "$root" ] || return 0
  [ -f "$root/.ncservo-release" ] || die "$root is not a root made by debian-root.sh; not deleting it"
  root=$(realpath "$root")
  # Innermost first; lazily, so a process still running inside cannot keep the root.
  grep -o " $root[^ ]*" /proc/self/mounts | sort -r | while read -r m; do umount -l "$m" 2>/dev/null || true; done
  if grep -q " $root[ /]" /proc/self/mounts; then die "$root still has mounts; not deleting it"; fi
  rm -rf "$root"
}

case "${1:-}" in
create) [ $# = 3 ] || die "usage: create RELEASE ROOT"; create "$2" "$3" ;;
run) [ $# -ge 3 ] || die "usage: run ROOT COMMAND..."; shift; run "$@" ;;
remove) [ $# = 2 ] || die "usage: remove ROOT"; remove "$2" ;;
purge) rm -rf "$cache" ;;
mirror) [ -n "$mirror" ] || die "no Debian archive in $apt_etc/sources.list.d/*.sources or $apt_etc/sources.list"; echo "$mirror" ;;
base) [ $# = 2 ] || die "usage: base RELEASE"; base_tarball "$2" ;;
has-base) [ $# = 2 ] || die "usage: has-base RELEASE"; has_base "$2" ;;
*) die "usage: create RELEASE ROOT | run ROOT COMMAND... | remove ROOT | purge | mirror | base RELEASE | has-base RELEASE" ;;
esac
