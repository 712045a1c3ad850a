#!/usr/bin/env bash
# Renders the training set at scale into DIR (default data/scale, which git ignores):
#   DIR/varied:  COUNT (default 300) `rae-trace dataset` sequences of --varied scenes (rooms and
#                open floors, textured metals, glass, plastics, emitters, thin poles and panels,
#                one to eight lights, moving objects, cameras from still to fast), 8 frames of
#                128x128, their sample counts cycling through 1, 2, 4 and 8 spp, references at
#                256 spp; a progress bar over all frames;
#   DIR/blender: BLENDER (default 48) Blender Cycles sequences (seeds 1..BLENDER, never the
#                held-out 2001-2004) in four groups at 1, 2, 4 and 8 spp, references at 256 spp,
#                where bpy is installed (pip install bpy==4.5.15).
# Sequences already there are kept, so an interrupted run continues. rae-trace takes about
# 12 s a sequence on 2 cores (an hour for 300); Blender about a minute.
#   bash scripts/render-training-set.sh DIR [COUNT] [BLENDER]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-data/scale}
count=${2:-300}
blender=${3:-48}
cargo build --release --locked -p rae-trace
target/release/rae-trace dataset "$out/varied" --count "$count"
if [ "$blender" -gt 0 ] && python3 -c "import bpy" 2>/dev/null; then
    quarter=$(( (blender + 3) / 4 ))
    for i in 0 1 2 3; do
        spp=$((1 << i))
        first=$((i * quarter + 1))
        last=$(( (i + 1) * quarter < blender ? (i + 1) * quarter : blender ))
        [ "$first" -le "$last" ] || continue
        echo "== Blender seeds $first-$last at $spp spp"
        # Blender prints a line per tile; only the script's progress lines are shown.
        python3 scripts/render-blender.py "$out/blender-${spp}spp" --seeds "$first-$last" --spp "$spp" | { grep '^b[0-9]' || true; }
    done
elif [ "$blender" -gt 0 ]; then
    echo "no bpy: the Blender training sequences are skipped (pip install bpy==4.5.15)"
fi
echo "training set in $out"
