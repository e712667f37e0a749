# Sourced by offline-base.sh and smoke.sh: the podman store their images go to.
#
# podman remembers the storage driver a store was first used with: a default store that ever ran
# without `--storage-driver vfs` (even `podman info`) refuses it afterwards ("database storage
# graph driver "" does not match ..."). So the scripts never pass --storage-driver; with
# STORAGE_DRIVER (default vfs, which works inside containers and VMs without overlay mounts) they
# use a store of their own, named by a private CONTAINERS_STORAGE_CONF: ROADGAZE_STORE (default
# /var/lib/roadgaze-containers as root, ~/.local/share/roadgaze-containers otherwise) holds the
# file and the images. To see them: CONTAINERS_STORAGE_CONF=$ROADGAZE_STORE/storage.conf podman
# images. STORAGE_DRIVER= (empty) uses podman's default store as configured; a
# CONTAINERS_STORAGE_CONF already set is used as it is.

roadgaze_podman_store() {
    [[ -z "${CONTAINERS_STORAGE_CONF:-}" ]] || return 0
    local driver="${STORAGE_DRIVER-vfs}" root runroot
    [[ -n "$driver" ]] || return 0
    if [[ "$(id -u)" -eq 0 ]]; then
        root="${ROADGAZE_STORE:-/var/lib/roadgaze-containers}"
        runroot="/run/roadgaze-containers-$driver"
    else
        root="${ROADGAZE_STORE:-${XDG_DATA_HOME:-$HOME/.local/share}/roadgaze-containers}"
        runroot="${XDG_RUNTIME_DIR:-/tmp/roadgaze-$(id -u)}/roadgaze-containers-$driver"
    fi
    mkdir -p "$root"
    printf '[storage]\ndriver = "%s"\ngraphroot = "%s"\nrunroot = "%s"\n' \
        "$driver" "$root/storage-$driver" "$runroot" > "$root/storage.conf"
    export CONTAINERS_STORAGE_CONF="$root/storage.conf"
}
