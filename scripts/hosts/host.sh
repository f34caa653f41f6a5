#!/usr/bin/env bash
# The other Blenders Glint is tested on, each in a Debian chroot of its own.
#
#   host.sh list              the hosts of hosts.conf, one name a line
#   host.sh make NAME         make the chroot (or find it cached); prints its path
#   host.sh run NAME CMD...   run CMD as root inside it, in the checkout (/glint)
#
# A chroot is made once per suite and package list: it lives in
# $GLINT_HOSTS_CACHE (default /var/cache/glint-hosts), outside the checkout, in
# a folder named by a hash of what went into it, so a warm run finds it and a
# changed package list makes a new one. Making one takes a few minutes and
# ~1.7 GB (debootstrap --variant=minbase, then apt). `run` mounts /proc, /sys,
# /dev and the checkout in a private mount namespace: they vanish with the
# command, and nothing is left mounted if it is killed.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cache=${GLINT_HOSTS_CACHE:-/var/cache/glint-hosts}
mirror=${GLINT_DEBIAN_MIRROR:-http://deb.debian.org/debian}
# Bumped when the way a chroot is made changes, so old ones are not reused.
recipe=2

die() { echo "host.sh: $*" >&2; exit 1; }

conf_line() {  # NAME -> "name suite extras"
  local line
  line=$(grep -E "^$1[[:space:]]" "$here/hosts.conf" || true)
  [[ -n $line ]] || die "no host '$1' in scripts/hosts/hosts.conf (have: $(list | tr '\n' ' '))"
  echo "$line"
}

list() { grep -vE '^\s*(#|$)' "$here/hosts.conf" | awk '{print $1}'; }

packages() {  # NAME -> the package list, one a line
  local extras
  extras=$(conf_line "$1" | awk '{print $3}')
  grep -vE '^\s*(#|$)' "$here/packages.txt"
  [[ $extras == - ]] || tr ',' '\n' <<<"$extras"
}

chroot_path() {
  local name=$1 suite key
  suite=$(conf_line "$name" | awk '{print $2}')
  key=$( { echo "recipe $recipe $suite"; packages "$name"; } | sha256sum | cut -c1-12)
  echo "$cache/$name-$suite-$key"
}

# Run a command in the chroot with the kernel file systems mounted, in a mount
# namespace of its own (nothing outlives it).
in_chroot() {
  local dir=$1; shift
  unshare --mount --propagation private -- bash -c '
    set -e
    dir=$1; src=$2; shift 2
    mount -t proc proc "$dir/proc"
    mount --rbind /sys "$dir/sys"
    mount --rbind /dev "$dir/dev"
    mkdir -p "$dir/glint"
    mount --bind "$src" "$dir/glint"
    exec chroot "$dir" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
      LANG=C.UTF-8 CI="${CI:-}" GLINT_HOST="${GLINT_HOST:-}" "$@"
  ' in_chroot "$dir" "$root" "$@"
}

make_host() {
  local name=$1 dir suite tmp
  dir=$(chroot_path "$name")
  suite=$(conf_line "$name" | awk '{print $2}')
  if [[ -f $dir/.glint-ready ]]; then echo "$dir"; return; fi
  mkdir -p "$cache"
  # Hosts are made side by side (scripts/test.sh): one apt at a time.
  command -v debootstrap >/dev/null || (
    flock 8
    command -v debootstrap >/dev/null && exit 0
    echo "host.sh: installing debootstrap" >&2
    apt-get update -qq >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >&2
  ) 8>"$cache/.lock-apt"
  exec 9>"$cache/.lock-$name"
  flock 9
  if [[ -f $dir/.glint-ready ]]; then echo "$dir"; return; fi
  tmp="$dir.partial"
  rm -rf "$tmp"
  echo "host.sh: making the $name chroot ($suite) in $dir; a few minutes" >&2
  debootstrap --variant=minbase "$suite" "$tmp" "$mirror" >"$cache/$name.debootstrap.log" 2>&1 ||
    { tail -20 "$cache/$name.debootstrap.log" >&2; die "debootstrap $suite failed (log: $cache/$name.debootstrap.log)"; }
  # sid's Release file can read as expired against this machine's clock.
  printf 'Acquire::Check-Valid-Until "false";\nAcquire::Languages "none";\n' >"$tmp/etc/apt/apt.conf.d/99glint"
  ln -sf ../proc/self/mounts "$tmp/etc/mtab"  # Blender lists the mounted file systems at start
  printf 'path-exclude=/usr/share/doc/*\npath-exclude=/usr/share/man/*\npath-exclude=/usr/share/locale/*\n' \
    >"$tmp/etc/dpkg/dpkg.cfg.d/99glint-nodoc"
  mapfile -t pkgs < <(packages "$name")
  in_chroot "$tmp" bash -c 'apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
      apt-get install -y -qq --no-install-recommends "$@" && apt-get clean' apt "${pkgs[@]}" \
    >"$cache/$name.apt.log" 2>&1 ||
    { tail -20 "$cache/$name.apt.log" >&2; die "installing packages in the $name chroot failed (log: $cache/$name.apt.log)"; }
  in_chroot "$tmp" blender --version 2>/dev/null | head -1 >"$tmp/.glint-blender-version" || true
  touch "$tmp/.glint-ready"
  mv "$tmp" "$dir"
  # Chroots of older recipes or package lists for this host are not used again.
  for old in "$cache/$name"-*; do
    [[ $old == "$dir" || ! -d $old ]] || rm -rf --one-file-system "$old"
  done
  echo "$dir"
}

case ${1:-} in
  list) list ;;
  make) [[ $# -eq 2 ]] || die "usage: host.sh make NAME"; make_host "$2" ;;
  path) [[ $# -eq 2 ]] || die "usage: host.sh path NAME"; chroot_path "$2" ;;
  run)
    [[ $# -ge 3 ]] || die "usage: host.sh run NAME CMD..."
    name=$2; shift 2
    dir=$(make_host "$name")
    GLINT_HOST=$name in_chroot "$dir" bash -c 'cd /glint && exec "$@"' run "$@"
    ;;
  *) die "usage: host.sh list | make NAME | path NAME | run NAME CMD..." ;;
esac
