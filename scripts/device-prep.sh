#!/usr/bin/env bash
# Prepares the folders a GPU session carries to the lent machine (docs/PERF.md "Next steps"):
#   .gl      the Vulkan and GL loader packages the device image lacks (/work/.library/device)
#   .devbin  rae-cli built from this checkout, and from each REV given (e.g. the last GPU
#            session's head) as .devbin/rae-cli-REV, for side-by-side runs
# Usage: bash scripts/device-prep.sh [REV ...]
# Then, with the device tool: run(carry=[".gl", ".devbin"], command='bash scripts/gpu-bench.sh
# "$OUT" .devbin/rae-cli .devbin/rae-cli-REV'). Both folders are git-ignored (.git/info/exclude).
set -euo pipefail
cd "$(dirname "$0")/.."
for d in /.gl/ /.devbin/; do
    grep -qxF "$d" .git/info/exclude || echo "$d" >>.git/info/exclude
done
if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
    echo "== downloading the loader packages into .gl"
    mkdir -p .gl /tmp/amd64/partial
    o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
    apt-get "${o[@]}" update
    (cd .gl && apt-get "${o[@]}" download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
mkdir -p .devbin
echo "== rae-cli from this checkout"
cargo build --release --locked -p rae-cli
cp target/release/rae-cli .devbin/rae-cli
for rev in "$@"; do
    echo "== rae-cli from $rev"
    tree=$(mktemp -d)
    git worktree add --detach "$tree" "$rev"
    # A target folder of its own, so that this checkout's build stays as it is.
    CARGO_TARGET_DIR="$PWD/target/device-prep" cargo build --release --locked -p rae-cli --manifest-path "$tree/Cargo.toml"
    cp target/device-prep/release/rae-cli ".devbin/rae-cli-$rev"
    git worktree remove --force "$tree"
done
ls -l .devbin .gl
