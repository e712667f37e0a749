#!/usr/bin/env bash
# Build a Debian base image with Python 3.11 for machines that reach no image registry.
#
#   sudo docker/offline-base.sh                 # -> localhost/debian-py:bookworm
#
# It bootstraps Debian bookworm (minbase + python3, python3-venv and the EGL/GLES libraries
# MediaPipe dlopens) from the Debian mirror apt already uses, and imports the tree as an image
# into podman (or docker, when podman is absent). Then build roadgaze on it:
#
#   podman build --build-arg BASE=localhost/debian-py:bookworm -f docker/Dockerfile -t roadgaze .
#
# Idempotent: does nothing when the image exists (FORCE=1 rebuilds it).
#
# Settings (environment):
#   BASE_IMAGE   image name to create            (default localhost/debian-py:bookworm)
#   SUITE        Debian suite                    (default bookworm; Python 3.11)
#   MIRROR       Debian mirror URL               (default: the first Debian mirror in apt's sources)
#   ENGINE       podman or docker                (default: podman if installed, else docker)
#   STORAGE_DRIVER  podman's storage driver      (default vfs: works in containers/VMs without overlay),
#                in a store of its own (ROADGAZE_STORE; docker/podman-store.sh says why); empty:
#                podman's default store
#   WORKDIR      where the root tree is built    (default: a temporary directory, removed afterwards)
#   FORCE=1      rebuild even if the image exists
set -euo pipefail

BASE_IMAGE="${BASE_IMAGE:-localhost/debian-py:bookworm}"
SUITE="${SUITE:-bookworm}"
PACKAGES="python3,python3-venv,libegl1,libgles2,ca-certificates"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=podman-store.sh
source "$here/podman-store.sh"
FORCE="${FORCE:-0}"

log() { printf 'offline-base: %s\n' "$*" >&2; }
die() { printf 'offline-base: error: %s\n' "$*" >&2; exit 1; }

[[ "$(id -u)" -eq 0 ]] || die "needs root (debootstrap creates device nodes and chowns files): run it with sudo"

# The container engine.
if [[ -z "${ENGINE:-}" ]]; then
    if command -v podman >/dev/null 2>&1; then ENGINE=podman
    elif command -v docker >/dev/null 2>&1; then ENGINE=docker
    else die "neither podman nor docker is installed (Debian/Ubuntu: apt-get install -y podman runc)"
    fi
fi
engine=("$ENGINE")
if [[ "$ENGINE" == podman ]]; then
    roadgaze_podman_store
    [[ -z "${CONTAINERS_STORAGE_CONF:-}" ]] || log "podman store: $CONTAINERS_STORAGE_CONF"
fi

if [[ "$FORCE" != 1 ]] && "${engine[@]}" image exists "$BASE_IMAGE" 2>/dev/null; then
    log "$BASE_IMAGE already exists ($ENGINE); nothing to do (FORCE=1 rebuilds it)"
    exit 0
fi
if [[ "$ENGINE" == docker ]] && [[ "$FORCE" != 1 ]] && docker image inspect "$BASE_IMAGE" >/dev/null 2>&1; then
    log "$BASE_IMAGE already exists (docker); nothing to do (FORCE=1 rebuilds it)"
    exit 0
fi

command -v debootstrap >/dev/null 2>&1 \
    || die "debootstrap is not installed (Debian/Ubuntu: apt-get install -y debootstrap)"

# The mirror: MIRROR, else the first Debian archive URI in apt's sources (deb822 or one-line
# format), skipping security and third-party repositories.
detect_mirror() {
    local files=() f uri
    [[ -f /etc/apt/sources.list ]] && files+=(/etc/apt/sources.list)
    for f in /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list; do
        [[ -f "$f" ]] && files+=("$f")
    done
    ((${#files[@]})) || return 1
    # deb822: "URIs: http://deb.debian.org/debian"; one-line: "deb [opts] http://... bookworm main"
    uri="$(
        for f in "${files[@]}"; do
            sed -n -e 's/^[[:space:]]*URIs:[[:space:]]*//p' \
                   -e 's/^[[:space:]]*deb[[:space:]]\+\(\[[^]]*\][[:space:]]\+\)\?\([^[:space:]]\+\).*/\2/p' "$f"
        done | tr ' ' '\n' | grep -E '^(https?|file)://' | grep -E '/debian/?$' \
             | grep -v -e security -e debian-debug -e ports | head -n1
    )"
    [[ -n "$uri" ]] || return 1
    printf '%s\n' "${uri%/}"
}
if [[ -z "${MIRROR:-}" ]]; then
    MIRROR="$(detect_mirror)" || die "no Debian mirror found in /etc/apt/sources.list{,.d}; set MIRROR=http://deb.debian.org/debian (or your local mirror)"
fi
log "engine: ${engine[*]}"
log "mirror: $MIRROR  suite: $SUITE  image: $BASE_IMAGE"

# The root tree.
cleanup_dir=""
if [[ -z "${WORKDIR:-}" ]]; then
    WORKDIR="$(mktemp -d /var/tmp/roadgaze-base.XXXXXX)"
    cleanup_dir="$WORKDIR"
fi
trap 'if [[ -n "$cleanup_dir" ]]; then rm -rf --one-file-system "$cleanup_dir"; fi' EXIT
rootfs="$WORKDIR/rootfs"
if [[ -d "$rootfs" ]]; then
    log "removing the previous tree $rootfs"
    rm -rf --one-file-system "$rootfs"
fi

start=$SECONDS
log "debootstrap --variant=minbase --include=$PACKAGES $SUITE (takes about a minute)"
debootstrap --variant=minbase --include="$PACKAGES" "$SUITE" "$rootfs" "$MIRROR" \
    > "$WORKDIR/debootstrap.log" 2>&1 \
    || { tail -n 30 "$WORKDIR/debootstrap.log" >&2; die "debootstrap failed (log above)"; }

# Slim it: no apt lists, caches, docs or man pages; apt inside the image points at the same mirror.
rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*.bin "$rootfs"/var/cache/apt/archives/*.deb \
       "$rootfs"/usr/share/doc/* "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/* \
       "$rootfs"/var/log/*.log "$rootfs"/var/log/apt/* "$rootfs"/debootstrap 2>/dev/null || true
printf 'deb %s %s main\n' "$MIRROR" "$SUITE" > "$rootfs/etc/apt/sources.list"
rm -f "$rootfs/etc/hostname" "$rootfs/etc/resolv.conf"
chroot "$rootfs" /usr/bin/python3 -c 'import venv, ensurepip' \
    || die "python3 (with venv and ensurepip) does not run in the new tree"
log "tree ready in $((SECONDS - start)) s: $(du -sh --one-file-system "$rootfs" | cut -f1)"

# Import: python3 on PATH as `python` too, like the python:3.11-slim images.
ln -sf python3 "$rootfs/usr/bin/python"
tar --numeric-owner -C "$rootfs" -c . | "${engine[@]}" import \
    --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    --change 'ENV LANG=C.UTF-8' \
    --change 'CMD ["/usr/bin/python3"]' \
    - "$BASE_IMAGE" >/dev/null
log "imported $BASE_IMAGE in $((SECONDS - start)) s total"
"${engine[@]}" images "$BASE_IMAGE"
