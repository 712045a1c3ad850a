#!/usr/bin/env bash
# The GPU measurements of docs/PERF.md in one run, for a lent NVIDIA machine:
#   build here:   bash scripts/device-prep.sh [REV ...]   (.devbin/rae-cli[-REV], loaders in .gl)
#   run there:    bash scripts/gpu-bench.sh "$OUT" .devbin/rae-cli [OTHER-BUILD ...]   (carrying .devbin and .gl)
# Checks the goldens on the GPU, times 1080p and 720p in f32 and f16 over conv tiles x weight
# memories (GPU-resident frames by timestamps, and host round trips), per-stage times, the sample
# sequence end to end, and PyTorch/cuDNN on the same weights (TF32 off, then on). Everything goes to $2/log.txt.
# TILES, MEMORIES, SOURCES (e.g. auto,sampled,storage; auto is per conv where tuned) and
# STAGE_TILES override the sweep; SKIP_TORCH=1 leaves PyTorch out; MMA=1 adds the matrix-unit
# kernel: it holds the split tiles (mma32x3) to
# PyTorch's goldens (`verify --tile`), prints every mma tile's error against the direct f32
# frames, times tuned-mma and fixed mma tiles beside the others, prints the stages of tuned-mma
# and denoises the sample with it (f32 and f16) for its PSNR against the direct one; MMA=only
# stops after that (one call within the device's 10-minute limit; the sweep in a second call).
# With several builds the sweep runs ROUNDS (default 2) interleaved rounds of each, for
# side-by-side ratios; everything else uses the first.
set -uo pipefail
out=${1:?output folder}
shift
cli=${1:?rae-cli binary}
builds=("$@")
rounds=${ROUNDS:-1}
[ ${#builds[@]} -gt 1 ] && rounds=${ROUNDS:-2}
tiles=${TILES:-tuned,16x2,4x1}
memories=${MEMORIES:-storage,uniform}
sources=()
[ -n "${SOURCES:-}" ] && sources=(--sources "$SOURCES")
mkdir -p "$out"
log="$out/log.txt"
# Vulkan loader: the image has the NVIDIA driver's ICD but no libvulkan (device README).
if ! ldconfig -p | grep -q libvulkan.so.1; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export WGPU_BACKEND=vulkan
w=models/rae-default.safetensors
{
    echo "== $(date -u +%FT%TZ) $(nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader)"
    "$cli" devices
    echo "== goldens"
    "$cli" verify tests/fixtures/golden_*.safetensors
    if [ -n "${MMA:-}" ]; then
        echo "== mma: the split tiles against PyTorch's goldens (must pass, as the direct kernel does), then the plain one (fails by design: f16 operands)"
        "$cli" verify tests/fixtures/golden_*.safetensors --tile mma32x3
        "$cli" verify tests/fixtures/golden_full_64x64.safetensors --tile mma16x3
        "$cli" verify tests/fixtures/golden_full_96x64.safetensors --tile mma64x3
        "$cli" verify tests/fixtures/golden_full_64x64.safetensors --tile mma32
        echo "== mma: each fixed tile on 64x64 against the direct f32 frames (the err column; emulated if no matrix units)"
        "$cli" bench "$w" --sizes 64x64 --frames 3 --precision f32,f16 --tile 16x2,mma16,mma32,mma48,mma64,mma16x3,mma32x3,mma48x3,mma64x3 --weights-memory storage
        echo "== mma: the same tiles emulated on this GPU (RAE_MATRIX_UNITS=0), for comparison"
        RAE_MATRIX_UNITS=0 "$cli" bench "$w" --sizes 64x64 --frames 3 --precision f32 --tile mma32,mma64,mma32x3 --weights-memory storage
        echo "== mma: 1080p and 720p"
        "$cli" bench "$w" --sizes 1920x1080,1280x720 --frames 20 --precision f32,f16 --tile tuned,tuned-mma,mma32,mma64,mma32x3,mma64x3 --weights-memory storage --peak-gflops 66900 | grep -E "^ +(size|[0-9]+x[0-9]+) "
        echo "== mma: stages of tuned-mma (f16, f32)"
        "$cli" bench "$w" --sizes 1920x1080 --frames 10 --precision f16,f32 --tile tuned-mma --weights-memory storage --layers
        echo "== mma: the sample with tuned-mma, f32 and f16"
        "$cli" denoise samples/random2026 --weights "$w" -o "$out/sample-mma32" --csv "$out/sample-mma-f32.csv" --tile tuned-mma
        "$cli" denoise samples/random2026 --weights "$w" -o "$out/sample-mma16" --csv "$out/sample-mma-f16.csv" --tile tuned-mma --precision f16
        rm -rf "$out/sample-mma32" "$out/sample-mma16"
        [ "$MMA" = only ] && exit 0
    fi
    for r in $(seq "$rounds"); do
        for b in "${builds[@]}"; do
            echo "== tiles x weight memory: $b, round $r"
            "$b" bench "$w" --sizes 1920x1080,1280x720 --frames 20 --precision f32,f16 --tile "$tiles" --weights-memory "$memories" ${sources[@]+"${sources[@]}"} --peak-gflops 66900 | grep -E "^ +(size|[0-9]+x[0-9]+) "
        done
    done
    echo "== stages"
    "$cli" bench "$w" --sizes 1920x1080 --frames 10 --precision f32 --tile "${STAGE_TILES:-tuned}" --weights-memory storage --layers
    echo "== sample"
    "$cli" denoise samples/random2026 --weights "$w" -o "$out/sample" --csv "$out/sample.csv"
    [ -n "${SKIP_TORCH:-}" ] && exit 0
    echo "== PyTorch"
    (cd weights-tool && python3 -m rae_weights bench ../"$w" --sizes 1920x1088,1280x736 --frames 20 --device cuda --dtypes float32,float16)
    echo "== PyTorch with TF32 convs (its default on this GPU: 10-bit mantissas in, as in rae's plain mma tiles)"
    (cd weights-tool && python3 -m rae_weights bench ../"$w" --sizes 1920x1088,1280x736 --frames 20 --device cuda --dtypes float32 --tf32)
} 2>&1 | tee "$log"
rm -rf "$out/sample"
