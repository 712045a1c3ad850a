#!/usr/bin/env bash
# One training round on a lent GPU machine, within a fixed time: renders fresh rae-trace training
# sequences on the machine's cores while the GPU trains on those already done, continuing from a
# shipped model, and brings the weights back.
#   build here:  bash scripts/gpu-train-prep.sh [BLENDER_FOLDER ...]   (.devbin, .whl, .devdata)
#   run there:   bash scripts/gpu-train.sh "$OUT"         (carrying .devbin, .whl and .devdata)
# Environment (defaults in brackets):
#   MINUTES [6]    training time; the learning rate's cosine runs over it (train --max-minutes)
#   INIT [models/rae-default.safetensors]   the model to continue from
#   SEQUENCES [400], FIRST_SEED [5001]      rae-trace --varied scenes to render (seeds from there)
#   TRAIN_ARGS []  more arguments for train
#   EXTRA []       more training folders, relative to weights-tool/ (e.g. ../.devdata/blender, the
#                  carried Blender sequences; a folder listed twice counts twice)
#   BATCH [16], LR [2e-4], SEED [21], START_AFTER [12] (sequences rendered before training starts)
#   DATA [/tmp/rae-train/varied]   where the sequences are rendered (those already there are kept)
#   DEVICE [cuda]  (cpu runs the same round here, to try the script before spending device time)
#   COLOR_INIT []  also train the color-only model (no albedo, no demodulation) from this file,
#                  alongside on the same GPU (one small network leaves most of it idle), with
#                  the same data, minutes and settings: OUT/color/
# Writes OUT/model.safetensors, OUT/log.csv (the loss), OUT/train.log and
# OUT/render.log. Nothing here needs Vulkan: rae-trace renders on the CPU.
set -uo pipefail
out=${1:?output folder}
cd "$(dirname "$0")/.."
mkdir -p "$out"
minutes=${MINUTES:-6}
init=${INIT:-models/rae-default.safetensors}
data=${DATA:-/tmp/rae-train/varied}
run=/tmp/rae-train/run
rm -rf "$run" "$run-color"
mkdir -p "$data"

if ! python3 -c "import OpenEXR" 2>/dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site
fi
device=${DEVICE:-cuda}
if command -v nvidia-smi >/dev/null; then nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; fi
python3 -c "import torch, OpenEXR; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())" || exit 1

# The renderer leaves two cores to each trainer (its Python thread and the GPU's feeding).
cores=$(nproc)
keep=$([ -n "${COLOR_INIT:-}" ] && echo 4 || echo 2)
RAYON_NUM_THREADS=$((cores > 2 * keep ? cores - keep : cores)) .devbin/rae-trace dataset "$data" \
    --count "${SEQUENCES:-400}" --first-seed "${FIRST_SEED:-5001}" >"$out/render.log" 2>&1 &
renderer=$!
# Training starts once START_AFTER sequences are there, or after two minutes with at least one.
need=${START_AFTER:-12}
rendered() { find "$data" -mindepth 1 -maxdepth 1 -name 'v*' -type d | wc -l; }
waited=0
while [ "$(rendered)" -lt "$need" ] && { [ "$waited" -lt 120 ] || [ "$(rendered)" -eq 0 ]; }; do
    kill -0 "$renderer" 2>/dev/null || { echo "rae-trace stopped early:"; cat "$out/render.log"; exit 1; }
    sleep 2
    waited=$((waited + 2))
done
echo "$(date -u +%T) $(rendered) sequences rendered; training for $minutes minutes"

# train INIT RUN OUT_DIR [ARGS...]: one trainer's round, its log in OUT_DIR/train.log. The
# weights file is the checkpoint that comes back (the one with Adam's moments, 18 MB, is over
# what returns from the machine; train --init continues from the weights).
train() {
    local init=$1 run=$2 dir=$3
    shift 3
    mkdir -p "$dir"
    (
        cd weights-tool &&
            PYTHONUNBUFFERED=1 python3 -m rae_weights train --data "$data" ${EXTRA:-} --out "$run" \
                --init "../$init" --skip prepool --device "$device" --batch "${BATCH:-16}" --lr "${LR:-2e-4}" \
                --seed "${SEED:-21}" --steps 1000000 --max-minutes "$minutes" --reload-every 30 \
                --val-every 200 --ckpt-every 1000 --threads 2 ${TRAIN_ARGS:-} "$@"
    ) >"$dir/train.log" 2>&1
    local rc=$?
    cp "$run/model.safetensors" "$run/log.csv" "$dir/" 2>/dev/null
    return $rc
}
color=
if [ -n "${COLOR_INIT:-}" ]; then
    train "$COLOR_INIT" "$run-color" "$out/color" --inputs color --no-demodulate &
    color=$!
fi
train "$init" "$run" "$out" &
main=$!
tail -n +1 -F "$out/train.log" --pid "$main" 2>/dev/null
wait "$main"
status=$?
if [ -n "$color" ]; then
    wait "$color" || status=1
    tail -n 3 "$out/color/train.log"
fi
kill "$renderer" 2>/dev/null
echo "$(date -u +%T) $(rendered) sequences rendered"
exit "$status"
