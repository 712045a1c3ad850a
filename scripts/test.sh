#!/usr/bin/env bash
# All of rae's tests, on a fresh machine: installs what is missing (lavapipe, the Python
# packages with PyTorch; for the page, the wasm-bindgen CLI, Chromium and Playwright), then
# checks the Rust formatting (rustfmt.toml) and runs the Rust tests on lavapipe, the page in a
# headless browser and the weights-tool tests.
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/env.sh

# Each step's header carries the seconds since the start, so a CI log shows where its time goes.
step() { echo "== [$SECONDS s] $*"; }

# weights-tool and its packages (PyTorch's wheel is large: ~2 minutes on a fresh machine).
# The report's test also needs pyoidn, flip-evaluator and matplotlib.
if ! python3 -c "import torch, numpy, safetensors, pytest, OpenEXR, pyoidn, flip_evaluator, matplotlib" >/dev/null 2>&1; then
  step "installing Python packages (torch, numpy, safetensors, pytest, OpenEXR, pyoidn, flip-evaluator, matplotlib)"
  python3 -m pip install -q --disable-pip-version-check torch numpy safetensors pytest OpenEXR pyoidn flip-evaluator matplotlib
fi

# On lavapipe unless the caller chose an adapter.
export WGPU_ADAPTER_NAME="${WGPU_ADAPTER_NAME:-llvmpipe}"

# Formatting first: it takes a second, and an unformatted tree fails before the long build.
step "rustfmt (rustfmt.toml)"
cargo fmt --version >/dev/null 2>&1 || rustup component add rustfmt
cargo fmt --all --check
cargo fmt --manifest-path scripts/spirv-val/Cargo.toml --check

# Metal and DX12: the workspace compiles for macOS and Windows (cargo check does not link, so
# neither platform's SDK is needed; running there is not tested here). The browser (wasm32,
# wgpu's WebGPU backend) is built and run by scripts/web-test.sh below.
step "other targets: cargo check for aarch64-apple-darwin (Metal), x86_64-pc-windows-msvc (DX12)"
rustup target add aarch64-apple-darwin x86_64-pc-windows-msvc >/dev/null
cargo check --locked -q --workspace --target aarch64-apple-darwin
cargo check --locked -q --workspace --target x86_64-pc-windows-msvc

step "Rust tests (workspace)"
cargo test --workspace --locked

step "the page in headless Chromium against PyTorch and native rae-core (scripts/web-test.sh)"
bash scripts/web-test.sh

step "fuzzing the readers, weights loader and command line (60 s; scripts/fuzz.sh)"
bash scripts/fuzz.sh 60

step "weights-tool tests (PyTorch)"
(cd weights-tool && python3 -m pytest -q)
step "all passed"
