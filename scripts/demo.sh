#!/usr/bin/env bash
# The main job on what the repository ships: denoise the sample sequence (rendered by rae-trace,
# with a reference) with the shipped default model, reporting time and error per frame.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
cargo run --release --locked -p rae-cli -- denoise samples/random2026 -o out/random2026 --png
