#!/usr/bin/env bash
# Install the system packages contactqvi needs (DOLFINx 0.9 and friends from Debian).
#
#   scripts/install-deps.sh [LIST...]   LIST defaults to scripts/packages.txt; other
#                                       lists (scripts/paraview/packages.txt) follow
#                                       the same rules and the same trixie pin.
#
# Idempotent: does nothing when every package of the list(s) is installed.
# On a Debian release older than trixie (13) it adds the trixie suite with a low
# pin (Pin-Priority 100) so that only the packages we ask for with `-t trixie`
# come from it; on trixie or newer it installs them from the release itself.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
lists=("$@")
[ ${#lists[@]} -gt 0 ] || lists=("$here/packages.txt")
mapfile -t packages < <(cat "${lists[@]}" | sed 's/#.*//' | grep -v -e '^\s*$' | tr -d ' \t')

# A package is missing when it is not installed or older than its minimum version.
missing=()
for spec in "${packages[@]}"; do
    pkg=${spec%%>=*}
    status=$(dpkg-query -W -f='${Status} ${Version}' "$pkg" 2>/dev/null || true)
    if [[ "$status" != "install ok installed "* ]]; then
        missing+=("$pkg")
    elif [[ "$spec" == *">="* ]] && ! dpkg --compare-versions "${status##* }" ge "${spec#*>=}"; then
        missing+=("$pkg")
    fi
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all ${#packages[@]} packages already installed"
    exit 0
fi
echo "install-deps: missing: ${missing[*]}"

sudo=""
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: need root or sudo" >&2; exit 1; }
    sudo="sudo"
fi

# Write stdin to a file of apt's configuration unless it already holds it (its time stamp
# tells whether the package lists are older than the sources, below).
write_unchanged() {
    local text
    text=$(cat)
    [ "$(cat "$1" 2>/dev/null)" = "$text" ] || printf '%s\n' "$text" | $sudo tee "$1" >/dev/null
}

# Installing from trixie upgrades base-files, after which /etc/os-release says 13:
# our own sources file is what tells that this system is really a pinned older one.
trixie_sources=/etc/apt/sources.list.d/contactqvi-trixie.sources
. /etc/os-release
target=()
if [ -f "$trixie_sources" ] || { [ "${ID:-}" = debian ] && [ "${VERSION_ID:-99}" -lt 13 ]; }; then
    echo "install-deps: Debian older than trixie: using trixie with Pin-Priority 100"
    write_unchanged "$trixie_sources" <<SRC
Types: deb
URIs: http://deb.debian.org/debian
Suites: trixie
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
    write_unchanged /etc/apt/preferences.d/contactqvi-trixie <<PIN
Package: *
Pin: release n=trixie
Pin-Priority: 100
PIN
    target=(-t trixie)
fi

# apt-get update leaves its mark on lists/partial. Lists updated within the hour, after the
# last change of the sources and pins, are used as they are (a fresh cloud machine updates
# them at boot); an install that then fails (a package superseded since: apt fetches every
# file before it installs any) is retried after an update.
lists=/var/lib/apt/lists/partial
fresh=""
if [ -d "$lists" ] && [ -n "$(find "$lists" -maxdepth 0 -mmin -60)" ] \
    && [ -z "$(find /etc/apt/sources.list /etc/apt/sources.list.d /etc/apt/preferences.d -newer "$lists" 2>/dev/null)" ]; then
    fresh=1
fi
# --force-unsafe-io: dpkg does not sync every file it unpacks (tens of thousands of headers
# come with DOLFINx's JIT: Boost, PETSc); as in Debian's container images. A crash of the
# machine in the seconds after the install could leave files empty.
apt_install() {
    echo "install-deps: apt-get install ${target[*]} ${missing[*]}"
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends \
        -o Dpkg::Options::=--force-unsafe-io "${target[@]}" "${missing[@]}"
}
if [ -n "$fresh" ] && apt_install; then
    echo "install-deps: done (package lists updated within the hour, not again)"
    exit 0
fi
echo "install-deps: apt-get update"
$sudo apt-get update -q
apt_install
echo "install-deps: done"
