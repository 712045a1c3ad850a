#!/usr/bin/env bash
# Fuzzes rae's readers, weights loader and command line for SECONDS in all (default 60):
#   bash scripts/fuzz.sh [SECONDS] [rae-fuzz options: --seed N, --targets exr,args, ...]
# Replays the kept cases under fuzz/regressions/ first, then runs every target (weights, golden,
# exr, multilayer, image, args) in turn on cases mutated from the sample sequence and the test
# fixtures. The last line gives the cases run per target and the findings; the exit status is
# non-zero on any panic, abort, hang (a case over 10 s), allocation past 5 GiB, or error that
# names no file. Findings are written to fuzz/crashes/ (git ignores it).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
seconds=${1:-60}
shift || true
# The test profile: what `cargo test` has built already (dependencies optimised).
cargo build --profile test --locked -q -p rae-fuzz
exec target/debug/rae-fuzz "$seconds" "$@"
