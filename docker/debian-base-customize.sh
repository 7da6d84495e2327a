#!/bin/sh
# mmdebstrap customize hook (scripts/container-check.sh): turn a minbase trixie
# chroot into what Debian's official `debian:trixie` image is, i.e. the clean-up
# debuerreotype does. mmdebstrap itself empties /var/lib/apt/lists and the apt
# caches afterwards.
#   debian-base-customize.sh ROOT MIRROR SECURITY_MIRROR
set -eu
root=$1 mirror=$2 security=$3

# deb822 sources instead of the one-line /etc/apt/sources.list mmdebstrap wrote.
keyring=/usr/share/keyrings/debian-archive-keyring.pgp
[ -e "$root$keyring" ] || keyring=/usr/share/keyrings/debian-archive-keyring.gpg
rm -f "$root/etc/apt/sources.list"
mkdir -p "$root/etc/apt/sources.list.d"
cat >"$root/etc/apt/sources.list.d/debian.sources" <<EOF
Types: deb
URIs: $mirror
Suites: trixie trixie-updates
Components: main
Signed-By: $keyring

Types: deb
URIs: $security
Suites: trixie-security
Components: main
Signed-By: $keyring
EOF

# apt and dpkg settings of the official image (debuerreotype-minimizing-config).
conf=$root/etc/apt/apt.conf.d
printf '%s\n' 'Apt::AutoRemove::SuggestsImportant "false";' >"$conf/docker-autoremove-suggests"
printf '%s\n' 'Dir::Cache::pkgcache "";' 'Dir::Cache::srcpkgcache "";' >"$conf/docker-clean"
printf '%s\n' 'Acquire::GzipIndexes "true";' >"$conf/docker-gzip-indexes"
printf '%s\n' 'Acquire::Languages "none";' >"$conf/docker-no-languages"
mkdir -p "$root/etc/dpkg/dpkg.cfg.d"
printf '%s\n' force-unsafe-io >"$root/etc/dpkg/dpkg.cfg.d/docker-apt-speedup"
# No services are started inside a container build.
printf '%s\n' '#!/bin/sh' 'exit 101' >"$root/usr/sbin/policy-rc.d"
chmod 755 "$root/usr/sbin/policy-rc.d"

# Nothing machine-specific or left over from the bootstrap.
: >"$root/etc/machine-id"
rm -f "$root/var/lib/dbus/machine-id" "$root/etc/hostname" "$root/etc/resolv.conf"
# (not /tmp: mmdebstrap keeps its apt configuration there until it has cleaned up,
# and cleans /tmp itself.)
rm -rf "$root"/var/cache/apt/* "$root"/var/log/apt/*
rm -f "$root"/var/log/dpkg.log "$root"/var/log/alternatives.log "$root"/var/log/bootstrap.log
