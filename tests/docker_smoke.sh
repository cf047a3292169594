#!/usr/bin/env bash
# Smoke test of the Dockerfile's runtime stage without a Docker engine (none runs on our
# machines): podman + runc (Debian packages), a local Debian base made with debootstrap, and
# the host-built release binary standing in for the builder stage. Starts the container,
# waits for its HEALTHCHECK, runs one WebSocket session against it (`seaarms load`), stops
# it with SIGTERM and checks that the session record reached the data volume.
# Not part of tests/run.sh (it downloads a Debian base, minutes); run by hand as root.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${SMOKE_WORK:-/tmp/seaarms-smoke}
port=${SMOKE_PORT:-18666}
export DEBIAN_FRONTEND=noninteractive
need=()
for c in podman runc debootstrap; do command -v $c >/dev/null || need+=("$c"); done
if [ ${#need[@]} -gt 0 ]; then apt-get update -qq && apt-get install -y -qq "${need[@]}" >/dev/null; fi
cargo build --release --quiet --bin seaarms
mkdir -p "$work"
# This sandbox refuses setrlimit inside containers: run without podman's default ulimits.
printf '[containers]\ndefault_ulimits = []\n' > "$work/containers.conf"
export CONTAINERS_CONF="$work/containers.conf"
if ! podman image exists localhost/debian-base:bookworm; then
  rm -rf "$work/rootfs"
  debootstrap --variant=minbase bookworm "$work/rootfs" >/dev/null
  tar -C "$work/rootfs" -c . | podman import - localhost/debian-base:bookworm >/dev/null
fi
# The builder stage, replaced by an image holding the host-built binary at the same path.
ctx="$work/ctx"; rm -rf "$ctx"; mkdir -p "$ctx/src/target/release"
cp target/release/seaarms "$ctx/src/target/release/seaarms"
printf 'FROM localhost/debian-base:bookworm\nCOPY src /src\n' > "$ctx/Prebuilt"
podman build -q --runtime runc -f "$ctx/Prebuilt" -t localhost/seaarms-prebuilt "$ctx" >/dev/null
# The runtime stage exactly as written in the Dockerfile.
awk '/^FROM \$\{RUNTIME_IMAGE\} AS runtime/{on=1} on' Dockerfile > "$ctx/Runtime"
sed -i '1i ARG RUNTIME_IMAGE\nFROM localhost/seaarms-prebuilt AS builder' "$ctx/Runtime"
podman build -q --format docker --runtime runc --build-arg RUNTIME_IMAGE=localhost/debian-base:bookworm \
  -f "$ctx/Runtime" -t localhost/seaarms-smoke "$ctx" >/dev/null
podman rm -f seaarms-smoke >/dev/null 2>&1 || true
podman volume rm -f seaarms-smoke-data >/dev/null 2>&1 || true
podman run -d --runtime runc --name seaarms-smoke --network host \
  -e SEAARMS_BIND="127.0.0.1:$port" -e SEAARMS_INSTRUCTOR_TOKEN=smoke \
  -v seaarms-smoke-data:/var/lib/seaarms/data localhost/seaarms-smoke >/dev/null
trap 'podman rm -f seaarms-smoke >/dev/null 2>&1 || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && break; sleep 0.2; done
echo "healthz: $(curl -sf "http://127.0.0.1:$port/healthz")"
echo "user in container: $(podman exec seaarms-smoke id -u)"
health=$(podman healthcheck run seaarms-smoke 2>/dev/null || true)
echo "HEALTHCHECK: ${health:-healthy}"
[ -z "$health" ] || [ "$health" = healthy ]
RUST_BACKTRACE=0 ./target/release/seaarms load --url "http://127.0.0.1:$port" --sessions 1 --observers 1 \
  --seconds 3 --instructor-token smoke | tee "$work/load.json"
grep -q '"errors": 0' "$work/load.json"
podman stop -t 10 seaarms-smoke >/dev/null
mnt=$(podman volume inspect seaarms-smoke-data --format '{{.Mountpoint}}')
echo "records database after stop:"; ls -l "$mnt/seaarms.db"
[ -s "$mnt/seaarms.db" ]
ls "$mnt/sessions/"*.csv >/dev/null
echo "docker smoke test: OK"
