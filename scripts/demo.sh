#!/usr/bin/env bash
# The engine on what the repository ships: every golden sequence through wgpu, error against
# PyTorch and time per frame.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
cargo run --release --locked -p rae-cli -- verify tests/fixtures/golden_*.safetensors
