#!/usr/bin/env bash
# Prepares what scripts/gpu-train.sh carries to a lent GPU machine (git-ignored folders):
#   .devbin/rae-trace   built here (the machine has no Rust), stripped
#   .whl                the OpenEXR wheel for the machine's Python 3.12 (its image lacks it)
#   .devdata/blender    Blender sequences made small (scripts/compact-exr.py), from each
#                       FOLDER given (e.g. render-blender.py output of seeds never held out)
# Usage: bash scripts/gpu-train-prep.sh [FOLDER ...]
# Then, with the device tool: run(carry=[".devbin", ".whl", ".devdata"], command='EXTRA="../.devdata/blender"
# bash scripts/gpu-train.sh "$OUT"'). The tree and the carried folders travel within 64 MiB.
set -euo pipefail
cd "$(dirname "$0")/.."
for d in /.devbin/ /.whl/ /.devdata/; do
    grep -qxF "$d" .git/info/exclude 2>/dev/null || echo "$d" >>.git/info/exclude
done
cargo build --release --locked -p rae-trace
mkdir -p .devbin
cp target/release/rae-trace .devbin/rae-trace
strip .devbin/rae-trace
if ! ls .whl/openexr-*cp312*.whl >/dev/null 2>&1; then
    python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
        --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 -d .whl OpenEXR
fi
rm -rf .devdata
for f in "$@"; do
    python3 scripts/compact-exr.py "$f" ".devdata/blender/$(basename "$f")"
done
du -sh .devbin .whl .devdata 2>/dev/null
echo "the tree and these travel within 64 MiB: $(git ls-files -z | du -ch --files0-from=- | tail -1 | cut -f1) tracked"
