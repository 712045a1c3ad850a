#!/usr/bin/env bash
# Renders the training and held-out sequences of docs/MODELS.md with rae-trace (every buffer,
# motion included), into DIR (default data/, which git ignores):
#   DIR/train: --random 1..12 and the cornell, glossy, firefly and glossy-moving scenes, 8 frames
#              of 128x128 at 1 spp, references at 256 spp;
#   DIR/val:   --random 1001..1003 and cornell-moving (held out: never trained on), references
#              at 512 spp;
#   DIR/val4:  the same held-out sequences at 4 spp (another noise seed), DIR/val's references
#              copied in;
#   DIR/val-aux-samples, DIR/val4-aux-samples: DIR/val and DIR/val4 with the auxiliary buffers
#              averaged over the color's samples as offline renderers write them (`--aux
#              samples`); the color is the same, bit for bit;
#   DIR/blender-val, DIR/blender-val4: four held-out Blender Cycles scenes (seeds 2001-2004, 8
#              frames of 128x128 as multi-layer EXRs, 1 and 4 spp, references at 256 spp;
#              scripts/render-blender.py), where bpy is installed (pip install bpy==4.5.15);
#   DIR/blender-glass, DIR/blender-glass4: four more held-out Blender scenes, those of seeds
#              2005-2040 with the most glass (seeds 2005, 2011, 2012, 2038; docs/MODELS.md,
#              "Glass at 1 spp"), the same way.
# A folder already there is kept, so an interrupted run continues. About 15 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-data}
cargo build --release --locked -p rae-trace
trace=target/release/rae-trace
render() { # FOLDER ARGS...
    local dir=$1
    shift
    if [ ! -d "$dir" ]; then
        echo "== $dir"
        "$trace" render "$@" --frames 8 --spp 1 --size 128x128 "$dir.partial" > /dev/null
        mv "$dir.partial" "$dir"
    fi
}
for s in $(seq 1 12); do render "$out/train/r$s" --random "$s" --ref-spp 256; done
for n in cornell glossy firefly glossy-moving; do render "$out/train/$n" --scene "$n" --ref-spp 256; done
for s in 1001 1002 1003; do render "$out/val/r$s" --random "$s" --ref-spp 512; done
render "$out/val/cornell-moving" --scene cornell-moving --ref-spp 512 --seed 7
render4() { # NAME ARGS...: a held-out sequence again at 4 spp, with DIR/val's references
    local name=$1 dir=$out/val4/$1
    shift
    if [ ! -d "$dir" ]; then
        echo "== $dir"
        "$trace" render "$@" --frames 8 --spp 4 --ref-spp 0 --seed 4 --size 128x128 "$dir.partial" > /dev/null
        cp "$out/val/$name"/reference_*.exr "$dir.partial/"
        mv "$dir.partial" "$dir"
    fi
}
for s in 1001 1002 1003; do render4 "r$s" --random "$s"; done
render4 cornell-moving --scene cornell-moving
sampled_aux() { # SET SPP NAME ARGS...: a held-out sequence again, its buffers from the samples
    local set=$1 spp=$2 name=$3 dir=$out/$1-aux-samples/$3
    shift 3
    if [ ! -d "$dir" ]; then
        echo "== $dir"
        "$trace" render "$@" --frames 8 --spp "$spp" --ref-spp 0 --size 128x128 --aux samples "$dir.partial" > /dev/null
        cp "$out/val/$name"/reference_*.exr "$dir.partial/"
        mv "$dir.partial" "$dir"
    fi
}
for s in 1001 1002 1003; do
    sampled_aux val 1 "r$s" --random "$s"
    sampled_aux val4 4 "r$s" --random "$s" --seed 4
done
sampled_aux val 1 cornell-moving --scene cornell-moving --seed 7
sampled_aux val4 4 cornell-moving --scene cornell-moving --seed 4
if python3 -c "import bpy" 2>/dev/null; then
    # Blender prints a line per tile; only the script's progress lines are shown.
    python3 scripts/render-blender.py "$out/blender-val" --seeds 2001-2004 | { grep '^b2' || true; }
    python3 scripts/render-blender.py "$out/blender-val4" --seeds 2001-2004 --spp 4 --reference-from "$out/blender-val" | { grep '^b2' || true; }
    python3 scripts/render-blender.py "$out/blender-glass" --seeds 2005,2011-2012,2038 | { grep '^b2' || true; }
    python3 scripts/render-blender.py "$out/blender-glass4" --seeds 2005,2011-2012,2038 --spp 4 --reference-from "$out/blender-glass" | { grep '^b2' || true; }
else
    echo "no bpy: the Blender held-out sets are skipped (pip install bpy==4.5.15)"
fi
echo "training and held-out sequences in $out"
