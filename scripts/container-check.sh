#!/usr/bin/env bash
# Build docker/Dockerfile and check the image: the flagship on 2 ranks and
# `make test` run inside it (`make container-check`).
#
#   scripts/container-check.sh [--cold] [--head]
#
# Engine: docker when its daemon answers, else podman (podman and runc installed
# from Debian when missing, configured by docker/containers.conf through
# CONTAINERS_CONF; the system's /etc/containers is left alone). Base image
# debian:trixie: used when present, else pulled, else (no registry reachable)
# made locally with mmdebstrap and docker/debian-base-customize.sh the way the
# official image is made, and imported under the official name.
#
# --cold  first removes the image, the base made here and podman's build cache,
#         so the measured build includes making the base and every layer.
# --head  builds the committed HEAD (git archive) instead of the working tree, e.g.
#         while uncommitted edits are under way.
#
# Environment: ENGINE (docker|podman), IMAGE (contactqvi), SHM_SIZE (1g),
# MIRROR, SECURITY_MIRROR (Debian mirrors for a local base), PULL_TIMEOUT (60 s).
# Prints and writes build/container/report.txt: build times, image size, checks.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo"
IMAGE=${IMAGE:-contactqvi}
SHM_SIZE=${SHM_SIZE:-1g}
MIRROR=${MIRROR:-http://deb.debian.org/debian}
SECURITY_MIRROR=${SECURITY_MIRROR:-http://deb.debian.org/debian-security}
PULL_TIMEOUT=${PULL_TIMEOUT:-60}
BASE=docker.io/library/debian:trixie
work=$repo/build/container
report=$work/report.txt
cold=0
head=0
for arg in "$@"; do
    case $arg in
        --cold) cold=1 ;;
        --head) head=1 ;;
        -h | --help) sed -n '2,/^set -euo/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "container-check: unknown argument $arg (see --help)" >&2; exit 2 ;;
    esac
done
mkdir -p "$work"
: >"$report"

log() { echo "container-check: $*" | tee -a "$report"; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.0f", b - a }'; }

sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"

# Debian packages for the host tools, from the system's own release.
apt_install() {
    local missing=() pkg
    for pkg in "$@"; do
        dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    log "installing ${missing[*]} from Debian"
    $sudo apt-get update -q >/dev/null
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}" >"$work/apt.log" 2>&1 \
        || { tail -20 "$work/apt.log" >&2; exit 1; }
}

# --- engine ---------------------------------------------------------------
engine=${ENGINE:-}
if [ -z "$engine" ]; then
    if command -v docker >/dev/null && docker info >/dev/null 2>&1; then
        engine=docker
    else
        engine=podman
    fi
fi
engine_cmd=("$engine")
if [ "$engine" = podman ]; then
    apt_install podman runc
    export CONTAINERS_CONF=$repo/docker/containers.conf
    engine_cmd=(env CONTAINERS_CONF="$CONTAINERS_CONF" podman)
fi
[ -z "$sudo" ] || engine_cmd=("$sudo" "${engine_cmd[@]}")
ce() { "${engine_cmd[@]}" "$@"; }
log "engine: $(ce --version 2>/dev/null | head -1)"
image_exists() { ce image inspect "$1" >/dev/null 2>&1; }

if [ $cold -eq 1 ]; then
    log "--cold: removing $IMAGE, $BASE and the build cache"
    ce rmi -f "$IMAGE" >/dev/null 2>&1 || true
    ce rmi -f "$BASE" >/dev/null 2>&1 || true
    if [ "$engine" = podman ]; then
        # Working containers left by interrupted builds hold their layers.
        ce ps -a --external --format '{{.ID}} {{.Names}}' | awk '$2 ~ /-working-container$/ { print $1 }' \
            | while read -r id; do ce rm -f "$id" >/dev/null; done
        ce image prune -f >/dev/null
    else
        ce builder prune -af >/dev/null
    fi
fi

# --- base image -------------------------------------------------------------
t_base=0
if image_exists "$BASE"; then
    log "base $BASE present"
else
    t0=$(now)
    if timeout "$PULL_TIMEOUT" "${engine_cmd[@]}" pull -q "$BASE" >"$work/pull.log" 2>&1; then
        log "base $BASE pulled"
    else
        log "base: no registry reachable ($(tail -1 "$work/pull.log" | cut -c1-100)); making it with mmdebstrap"
        apt_install mmdebstrap
        tar=$work/debian-trixie.tar
        rm -f "$tar"
        # --skip=chroot/policy-rc.d: else mmdebstrap removes the hook's policy-rc.d.
        $sudo mmdebstrap --variant=minbase --format=tar --skip=chroot/policy-rc.d \
            --customize-hook="sh '$repo/docker/debian-base-customize.sh' \"\$1\" '$MIRROR' '$SECURITY_MIRROR'" \
            trixie "$tar" \
            "deb $MIRROR trixie main" "deb $MIRROR trixie-updates main" "deb $SECURITY_MIRROR trixie-security main" \
            >"$work/mmdebstrap.log" 2>&1 || { tail -20 "$work/mmdebstrap.log" >&2; exit 1; }
        ce import --change 'CMD ["bash"]' "$tar" "$BASE" >"$work/import.log" 2>&1 \
            || { cat "$work/import.log" >&2; exit 1; }
        rm -f "$tar"
    fi
    t_base=$(since "$t0")
    log "base made in ${t_base} s"
fi

# --- build ------------------------------------------------------------------
context=.
if [ $head -eq 1 ]; then
    context=$work/context
    rm -rf "$context"
    mkdir -p "$context"
    git archive HEAD | tar -x -C "$context"
    # One fixed mtime: buildah's COPY cache key includes it, and git archive stamps
    # every file with the commit time, which would rebuild the apt layer per commit.
    find "$context" -exec touch -h -d '2000-01-01 00:00:00 UTC' {} +
    log "context: HEAD $(git rev-parse --short HEAD) (git archive)"
else
    log "context: the working tree$(git diff --quiet HEAD -- 2>/dev/null || echo ' (with uncommitted changes)')"
fi
load=$(cut -d' ' -f1-3 /proc/loadavg)
t0=$(now)
build_args=(build -f "$context/docker/Dockerfile" -t "$IMAGE")
# podman: the host network, so no bridge or slirp is needed for apt in the build.
[ "$engine" = podman ] && build_args+=(--network=host)
ce "${build_args[@]}" "$context" >"$work/build.log" 2>&1 || { tail -30 "$work/build.log" >&2; exit 1; }
t_build=$(since "$t0")
size=$(ce image inspect --format '{{.Size}}' "$IMAGE")
log "image $IMAGE built in ${t_build} s (+ ${t_base} s base; $(nproc) cores, load average before: $load, after: $(cut -d' ' -f1-3 /proc/loadavg))"
log "image size $(awk -v s="$size" 'BEGIN { printf "%.2f GB (%.0f bytes)", s / 1e9, s }')"

# --- checks inside the image ------------------------------------------------
# No network: the checks must pass with what the image holds.
run=(run --rm --network=none --shm-size="$SHM_SIZE")
t0=$(now)
ce "${run[@]}" "$IMAGE" mpirun -n 2 python demos/coulomb3d.py --lev 3 --output /tmp/out >"$work/demo.log" 2>&1 \
    || { tail -30 "$work/demo.log" >&2; log "FAILED: flagship on 2 ranks (log: $work/demo.log)"; exit 1; }
log "flagship (mpirun -n 2, lev 3): exit 0 in $(since "$t0") s: $(grep -m1 'converged after' "$work/demo.log" || tail -1 "$work/demo.log")"

t0=$(now)
ce "${run[@]}" "$IMAGE" make test >"$work/test.log" 2>&1 \
    || { tail -30 "$work/test.log" >&2; log "FAILED: make test (log: $work/test.log)"; exit 1; }
log "make test: exit 0 in $(since "$t0") s: $(grep -a -E '[0-9]+ (passed|failed)' "$work/test.log" | awk '!seen[$0]++' | paste -sd';')"
log "OK (report: $report)"
