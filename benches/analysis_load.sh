#!/usr/bin/env bash
# HTTP throughput of POST /api/analysis (issue target: >= 5,000 requests/s on 2 cores).
# Starts the release server on a loopback port, drives it with wrk (Debian package `wrk`)
# for a bounded time, prints wrk's report, and stops the server.
# Usage: bash benches/analysis_load.sh [seconds=10] [connections=32]
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-10}
conns=${2:-32}
port=${SEAARMS_LOAD_PORT:-18089}
command -v wrk >/dev/null || { echo "install wrk (apt-get install wrk)" >&2; exit 1; }
cargo build --release --quiet
./target/release/seaarms --bind "127.0.0.1:$port" >/dev/null 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && break; sleep 0.1; done
lua=$(mktemp --suffix=.lua)
cat >"$lua" <<'LUA'
wrk.method = "POST"
wrk.headers["Content-Type"] = "application/json"
wrk.body = '{"robot": "magnum", "q": [0.1, 0.6, -1.1, 0.4, 0.2, 0.3], "rows": [0, 1, 2]}'
done = function(summary, latency, requests)
  io.write(string.format("requests/s: %.0f  non-2xx: %d  errors: %d\n",
    summary.requests / (summary.duration / 1e6), summary.errors.status,
    summary.errors.connect + summary.errors.read + summary.errors.write + summary.errors.timeout))
end
LUA
wrk -t2 -c"$conns" -d"${secs}s" --latency -s "$lua" "http://127.0.0.1:$port/api/analysis"
rm -f "$lua"
