#!/usr/bin/env bash
# Smoke test of the deployment on one host: build localhost/roadgaze:latest, then run a Zenoh
# router container (`roadgaze router`), the daemon container on a mounted recorded video and a
# listener container, on mutual TLS with access control (the files of `roadgaze security init`,
# made in the image). Exits 0 only when yaw messages and an alert reached the listener, the
# image's health check passed against the running daemon and the router refused a session
# without a certificate and a forged alert. Removes every container, network and file it made.
#
#   sudo docker/smoke.sh                     (from anywhere in a clone; podman, else docker)
#
# Needs root (or a working rootless podman/docker) and a few minutes; .ci/run runs it where
# podman works.
#
# Settings (environment):
#   ENGINE=podman|docker     default: podman if installed, else docker
#   IMAGE                    default localhost/roadgaze:latest
#   SKIP_BUILD=1             use the existing IMAGE
#   BASE                     base image; default: localhost/debian-py:bookworm when it exists
#                            (docker/offline-base.sh makes it), else python:3.11-slim if the
#                            registry answers, else offline-base.sh is run first
#   PIP_CERT / BUILD_CA_BUNDLE   a CA bundle pip needs (TLS-intercepting proxy): mounted for the
#                            build only
#   VIDEO=FILE               recorded drive to play (default: `roadgaze demo` makes one in the
#                            image: a synthetic drive with glances that raise alerts)
#   NETWORK=host|bridge      host: everything on 127.0.0.1 (default); bridge: a private network
#   SECURE=0                 plain TCP without certificates or access control (default 1)
#   PORT                     router port (default 7447; with NETWORK=host it must be free)
#   RUNTIME                  podman --runtime (e.g. runc where crun fails on the host's cgroups)
#   STORAGE_DRIVER           podman's storage driver, default vfs, in a store of its own
#                            (ROADGAZE_STORE, shared with offline-base.sh; docker/podman-store.sh);
#                            empty: podman's default store
#   KEEP=1                   keep containers and the work folder for inspection
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/.." && pwd)"
IMAGE="${IMAGE:-localhost/roadgaze:latest}"
NETWORK="${NETWORK:-host}"
PORT="${PORT:-7447}"
VEHICLE="smoke-$$"
SECURE="${SECURE:-1}"
START_TIMEOUT="${START_TIMEOUT:-180}"   # container start -> first yaw at the listener
RUN_TIMEOUT="${RUN_TIMEOUT:-240}"       # the whole drive

step=0
say() { printf '\n== %s\n' "$*"; }
info() { printf '   %s\n' "$*"; }
fail() { printf '\nSMOKE FAILED: %s\n' "$*" >&2; exit 1; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

# ---------------------------------------------------------------------------------- engine
if [[ -z "${ENGINE:-}" ]]; then
    if command -v podman >/dev/null 2>&1; then ENGINE=podman
    elif command -v docker >/dev/null 2>&1; then ENGINE=docker
    else fail "neither podman nor docker is installed (Debian/Ubuntu: apt-get install -y podman runc)"
    fi
fi
if [[ "$ENGINE" == docker ]] && ! docker info >/dev/null 2>&1; then
    fail "docker is installed but its daemon does not answer (start it, or install podman)"
fi
engine=("$ENGINE")
run_opts=()
if [[ "$ENGINE" == podman ]]; then
    # shellcheck source=podman-store.sh
    source "$here/podman-store.sh"
    roadgaze_podman_store
    [[ -n "${RUNTIME:-}" ]] && run_opts+=(--runtime "$RUNTIME")
fi
e() { "${engine[@]}" "$@"; }

work="$(mktemp -d /tmp/roadgaze-smoke.XXXXXX)"
chmod 0755 "$work"
containers=()
network=""
cleanup() {
    local rc=$?
    if [[ "${KEEP:-0}" == 1 ]]; then
        printf '\nKEEP=1: containers %s and %s left in place\n' "${containers[*]:-none}" "$work"
        exit "$rc"
    fi
    for c in "${containers[@]}"; do e rm -f -t 2 "$c" >/dev/null 2>&1 || e rm -f "$c" >/dev/null 2>&1 || true; done
    [[ -n "$network" ]] && { e network rm -f "$network" >/dev/null 2>&1 || true; }
    rm -rf "$work"
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

say "engine: $("${engine[@]}" --version)${CONTAINERS_STORAGE_CONF:+, store $CONTAINERS_STORAGE_CONF}"
t_total=$(now)

# ----------------------------------------------------------------------------------- build
if [[ "${SKIP_BUILD:-0}" != 1 ]]; then
    if [[ -z "${BASE:-}" ]]; then
        if e image inspect localhost/debian-py:bookworm >/dev/null 2>&1; then
            BASE=localhost/debian-py:bookworm
        elif timeout 90 "${engine[@]}" pull -q python:3.11-slim >/dev/null 2>&1; then
            BASE=python:3.11-slim
        else
            say "no image registry: making the Debian base with docker/offline-base.sh"
            ENGINE="$ENGINE" "$here/offline-base.sh"
            BASE=localhost/debian-py:bookworm
        fi
    fi
    build=(build --network host --build-arg "BASE=$BASE" -t "$IMAGE" -f "$here/Dockerfile")
    [[ "$ENGINE" == podman ]] && build+=(--format docker --isolation chroot)   # keep HEALTHCHECK
    ca="${BUILD_CA_BUNDLE:-${PIP_CERT:-}}"
    if [[ -n "$ca" ]]; then
        [[ "$ENGINE" == podman ]] || fail "BUILD_CA_BUNDLE/PIP_CERT needs podman (docker build has no --volume)"
        build+=(--volume "$ca:/run/build-ca.crt:ro" --build-arg PIP_CERT=/run/build-ca.crt)
    fi
    say "build $IMAGE on $BASE (several minutes the first time)"
    t=$(now)
    e "${build[@]}" "$repo" > "$work/build.log" 2>&1 \
        || { tail -n 40 "$work/build.log" >&2; fail "image build failed (log above)"; }
    info "built in $(since "$t") s; size $(e image inspect --format '{{.Size}}' "$IMAGE" | awk '{printf "%.0f MB", $1/1e6}')"
    # The build stage's image (about 1.4 GB, untagged; podman keeps it) is of no further use.
    e image prune -f --filter label=org.roadgaze.stage=build >/dev/null 2>&1 || true
else
    e image inspect "$IMAGE" >/dev/null 2>&1 || fail "SKIP_BUILD=1 but there is no image $IMAGE"
fi

# ------------------------------------------------------------------- can containers run here?
say "container check: roadgaze --version and the baked-in model"
probe() { e run --rm "${run_opts[@]}" --network host --no-healthcheck "$IMAGE" model verify > "$work/probe.log" 2>&1; }
if ! probe; then
    if grep -q 'rlimit' "$work/probe.log" && [[ "$ENGINE" == podman ]]; then
        info "setrlimit refused: retrying with default_ulimits = [] (CONTAINERS_CONF)"
        printf '[containers]\ndefault_ulimits = []\n' > "$work/containers.conf"
        export CONTAINERS_CONF="$work/containers.conf"
    elif grep -qi 'cgroup' "$work/probe.log" && [[ "$ENGINE" == podman ]] && [[ -z "${RUNTIME:-}" ]] \
        && command -v runc >/dev/null 2>&1; then
        info "the default runtime failed on cgroups: retrying with --runtime runc"
        run_opts+=(--runtime runc)
    fi
    probe || { cat "$work/probe.log" >&2; fail "a container of $IMAGE does not start"; }
fi
info "$(e run --rm "${run_opts[@]}" --network host --no-healthcheck "$IMAGE" --version 2>/dev/null) / $(grep -m1 ok "$work/probe.log")"

# ----------------------------------------------------------------------------------- video
mkdir -p "$work/data"
if [[ -n "${VIDEO:-}" ]]; then
    [[ -r "$VIDEO" ]] || fail "VIDEO=$VIDEO is not a readable file"
    cp "$VIDEO" "$work/data/drive.mp4"
else
    say "recording a synthetic drive (roadgaze demo in the image)"
    t=$(now)
    mkdir -p "$work/demo"; chmod 0777 "$work/demo"
    e run --rm "${run_opts[@]}" --network host --no-healthcheck -v "$work/demo:/out" \
        "$IMAGE" demo --out /out > "$work/demo.log" 2>&1 \
        || { tail -n 20 "$work/demo.log" >&2; fail "roadgaze demo failed"; }
    cp "$work/demo/drive.mp4" "$work/data/drive.mp4"
    info "drive.mp4 in $(since "$t") s ($(grep -c . "$work/demo/alerts.jsonl") alerts expected)"
fi
# The daemon runs as uid 10001: the file and its folder must be world-readable.
chmod 0755 "$work/data"; chmod 0644 "$work/data/drive.mp4"

# ------------------------------------------------------------------------------ containers
say "containers: router, listener, daemon (network: $NETWORK)"
net_opts=(--network host); router_host=127.0.0.1; listen_ep="tcp/127.0.0.1:$PORT"
if [[ "$NETWORK" == bridge ]]; then
    network="roadgaze-smoke-$$"
    e network create "$network" >/dev/null
    net_opts=(--network "$network"); router_host="roadgaze-smoke-router-$$"; listen_ep="tcp/0.0.0.0:$PORT"
elif (exec 3<>"/dev/tcp/127.0.0.1/$PORT") 2>/dev/null; then
    fail "port $PORT on 127.0.0.1 is in use (PORT=... to choose another)"
fi
router="roadgaze-smoke-router-$$"; listener="roadgaze-smoke-listener-$$"; daemon="roadgaze-smoke-daemon-$$"
if [[ "$SECURE" == 1 ]]; then
    # Certificates and Zenoh files made by the image itself (owned by its user, uid 10001), the
    # paths written as mounted below; the CA key stays in the work folder.
    t=$(now)
    mkdir -p "$work/zenoh"; chmod 0777 "$work/zenoh"
    sec_endpoint="tls/127.0.0.1:$PORT"; sec_listen="$sec_endpoint"
    [[ "$NETWORK" == bridge ]] && { sec_endpoint="tls/$router_host:$PORT"; sec_listen="tls/0.0.0.0:$PORT"; }
    e run --rm "${run_opts[@]}" --network host --no-healthcheck -v "$work/zenoh:/out" "$IMAGE" \
        security init /out/bundle --vehicle-id "$VEHICLE" --consumer listener --consumer health \
        --consumer intruder --endpoint "$sec_endpoint" --listen "$sec_listen" \
        --path-root /etc/roadgaze/zenoh > "$work/security.log" 2>&1 \
        || { cat "$work/security.log" >&2; fail "roadgaze security init failed"; }
    info "security init in $(since "$t") s: mutual TLS on $sec_listen, access control for $VEHICLE"
    vol() { printf '%s\n' -v "$work/zenoh/bundle/$1:/etc/roadgaze/zenoh/$1:ro"; }
    zfile() { printf '/etc/roadgaze/zenoh/%s/zenoh.json5' "$1"; }
    router_args=(router --zenoh-config "$(zfile router)")
    mapfile -t router_opts < <(vol router)
    listener_args=(--zenoh-config "$(zfile consumer-listener)")
    mapfile -t listener_opts < <(vol consumer-listener; vol consumer-intruder)
    daemon_args=(--zenoh-config "$(zfile daemon)")
    # the image's health check asks as the consumer "health"
    mapfile -t daemon_opts < <(vol daemon; vol consumer-health)
    daemon_opts+=(-e "ROADGAZE__ZENOH__CONFIG_FILE=$(zfile consumer-health)")
    zenv=(-e "ROADGAZE__ZENOH__VEHICLE_ID=$VEHICLE")
else
    router_args=(router --listen "$listen_ep"); router_opts=(); listener_args=(); listener_opts=()
    daemon_args=(); daemon_opts=()
    zenv=(-e ROADGAZE__ZENOH__MODE=client -e "ROADGAZE__ZENOH__CONNECT=[\"tcp/$router_host:$PORT\"]"
          -e ROADGAZE__ZENOH__MULTICAST_SCOUTING=false -e "ROADGAZE__ZENOH__VEHICLE_ID=$VEHICLE")
fi
t=$(now)
containers+=("$router")
e create "${run_opts[@]}" "${net_opts[@]}" --name "$router" --hostname "$router" --init --no-healthcheck \
    "${router_opts[@]}" "$IMAGE" "${router_args[@]}" >/dev/null
containers+=("$listener")
e create "${run_opts[@]}" "${net_opts[@]}" --name "$listener" --init --no-healthcheck "${zenv[@]}" \
    "${listener_opts[@]}" "$IMAGE" listen --json --vehicle-id "$VEHICLE" --timeout "$RUN_TIMEOUT" \
    "${listener_args[@]}" >/dev/null
containers+=("$daemon")
e create "${run_opts[@]}" "${net_opts[@]}" --name "$daemon" --init "${zenv[@]}" -v "$work/data:/data:ro" \
    "${daemon_opts[@]}" "$IMAGE" run --source /data/drive.mp4 "${daemon_args[@]}" >/dev/null
info "created in $(since "$t") s"

e start "$router" >/dev/null
deadline=$((SECONDS + 60))
until e logs "$router" 2>&1 | grep -q 'listening on'; do
    [[ "$(e inspect --format '{{.State.Running}}' "$router")" == true ]] \
        || { e logs "$router" >&2; fail "the router container exited"; }
    (( SECONDS < deadline )) || { e logs "$router" >&2; fail "the router does not listen on $PORT after 60 s"; }
    sleep 0.5
done
info "router: $(e logs "$router" 2>&1 | grep -m1 -o 'zenoh router [0-9a-f]* listening on [^"]*')"

e start "$listener" >/dev/null
sleep 3   # let the listener open its session and subscribe

t_start=$(now)
e start "$daemon" > "$work/start.err" 2>&1 || { cat "$work/start.err" >&2; fail "the daemon container did not start"; }
info "daemon started"

# -------------------------------------------------------------------------------- checks
count() { e logs "$listener" 2>/dev/null | grep -c "\"type\": \"$1\"" || true; }
deadline=$((SECONDS + START_TIMEOUT))
until (( $(count yaw) > 0 )); do
    [[ "$(e inspect --format '{{.State.Running}}' "$daemon")" == true ]] \
        || { e logs "$daemon" | tail -n 30 >&2; fail "the daemon exited before any yaw reached the listener"; }
    (( SECONDS < deadline )) || { e logs "$daemon" | tail -n 30 >&2; fail "no yaw message after $START_TIMEOUT s"; }
    sleep 0.2
done
startup=$(since "$t_start")
info "first yaw message at the listener ${startup} s after the daemon container started"

say "health check (the image's HEALTHCHECK, against the running daemon)"
health=fail
deadline=$((SECONDS + 60))
while (( SECONDS < deadline )); do
    [[ "$(e inspect --format '{{.State.Running}}' "$daemon")" == true ]] || break
    if [[ "$ENGINE" == podman ]]; then
        if e healthcheck run "$daemon" > "$work/health.out" 2>&1; then health=ok; break; fi
    else
        cmd="$(e image inspect --format '{{index .Config.Healthcheck.Test 1}}' "$IMAGE")"
        if e exec "$daemon" sh -c "$cmd" > "$work/health.out" 2>&1; then health=ok; break; fi
    fi
    sleep 2
done
info "health check: $health"
[[ "$health" == ok ]] || { cat "$work/health.out" >&2; fail "the health check did not pass while the daemon ran"; }

refused="not checked (SECURE=0)"
if [[ "$SECURE" == 1 ]]; then
    say "access control: what the router must refuse"
    # A session without a certificate (plain TCP on the TLS port) must not reach the daemon.
    if e exec "$listener" roadgaze listen --query-state --timeout 5 --vehicle-id "$VEHICLE" \
        --zenoh-mode client --zenoh-connect "tcp/$router_host:$PORT" > "$work/plain.out" 2>&1; then
        cat "$work/plain.out" >&2; fail "a session without a certificate got the daemon's state"
    fi
    info "no certificate (plain TCP): refused: $(tail -n 1 "$work/plain.out" | cut -c 1-100)"
    # A well-formed alert for this vehicle, sent with another consumer's certificate: the router's
    # access control must drop it (only the daemon's certificate may put alerts).
    e exec "$listener" python -c '
import json, sys, time, zenoh
from roadgaze.transport import AlertMessage
vehicle, path = sys.argv[1], sys.argv[2]
alert = AlertMessage(vehicle_id=vehicle, seq=0, kind="driver_unavailable", level="critical",
                     t_s=4242.5, wall_time=time.time(), yaw_deg=0.0, off_road_s=0.0,
                     window_off_road_s=0.0)
with zenoh.open(zenoh.Config.from_file(path)) as session:
    time.sleep(1.0)
    session.put(f"vehicle/{vehicle}/dms/alert", alert.to_json_bytes())
    time.sleep(1.0)
print("forged alert sent")
' "$VEHICLE" "$(zfile consumer-intruder)" > "$work/forge.out" 2>&1 \
        || { cat "$work/forge.out" >&2; fail "could not send the forged alert (the check itself failed)"; }
    refused="yes"
fi

say "waiting for the drive to end (alerts)"
deadline=$((SECONDS + RUN_TIMEOUT))
while [[ "$(e inspect --format '{{.State.Running}}' "$daemon")" == true ]]; do
    (( SECONDS < deadline )) || fail "the daemon still runs after $RUN_TIMEOUT s"
    sleep 1
done
daemon_rc="$(e inspect --format '{{.State.ExitCode}}' "$daemon")"
sleep 1
e logs "$listener" > "$work/listener.jsonl" 2>/dev/null || true
yaws=$(grep -c '"type": "yaw"' "$work/listener.jsonl" || true)
alerts=$(grep -c '"type": "alert"' "$work/listener.jsonl" || true)
grep '"type": "alert"' "$work/listener.jsonl" \
    | sed -e 's/.*"kind": "\([^"]*\)", "level": "\([^"]*\)", "t_s": \([0-9.]*\).*/\1 \2 \3/' \
    | while read -r kind level t_s; do LC_ALL=C printf '   alert: %s %s at t=%.2f s\n' "$kind" "$level" "$t_s"; done || true

say "router log: the sessions it served"
e logs "$router" 2>&1 | grep -o '"message": "session [^"]*"' | sed -e 's/"message": "\(.*\)"/   \1/' || true

say "result"
info "image:         $IMAGE ($(e image inspect --format '{{.Size}}' "$IMAGE" | awk '{printf "%.0f MB", $1/1e6}'))"
info "start-up:      ${startup} s (container start -> first yaw at the listener)"
info "yaw messages:  $yaws"
info "alerts:        $alerts"
info "health check:  $health"
info "daemon exit:   $daemon_rc"
info "refused:       $refused (a session without a certificate; a consumer's forged alert)"
info "total:         $(since "$t_total") s"
if [[ "$SECURE" == 1 ]] && e logs "$listener" 2>&1 | grep -q '4242\.5'; then
    refused="NO"; info "forged alert:  reached the listener"
    fail "the forged alert reached the listener: access control did not apply"
fi
(( yaws > 0 )) || fail "no yaw message reached the listener"
(( alerts > 0 )) || fail "no alert reached the listener"
[[ "$daemon_rc" == 0 ]] || { e logs "$daemon" | tail -n 30 >&2; fail "the daemon exited with $daemon_rc"; }
printf '\nSMOKE OK\n'
