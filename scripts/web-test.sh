#!/usr/bin/env bash
# The page in a real browser: builds it (scripts/web.sh --build-only), denoises the sample with
# native rae-core (rae-cli, on lavapipe unless WGPU_ADAPTER_NAME says otherwise), then opens the
# page in headless Chromium (WebGPU through SwiftShader) and holds it to PyTorch's golden frames
# and to the native output (tests/web/page_test.py). Installs Debian's chromium and Playwright
# from PyPI where missing. The last line gives the largest differences and the ms per frame.
#   bash scripts/web-test.sh [--screenshot PATH]    (default target/web-test/page.png)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
export WGPU_ADAPTER_NAME="${WGPU_ADAPTER_NAME:-llvmpipe}"

if ! command -v chromium >/dev/null 2>&1; then
  echo "== installing chromium (Debian)"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq chromium >/dev/null
fi
if ! python3 -c "import playwright, numpy, OpenEXR" >/dev/null 2>&1; then
  echo "== installing playwright, numpy, OpenEXR (PyPI)"
  python3 -m pip install -q --disable-pip-version-check playwright numpy OpenEXR
fi

bash scripts/web.sh --build-only

echo "== the sample with native rae-core (rae-cli, the test profile)"
cargo build --profile test --locked -q -p rae-cli
native=$(mktemp -d)
trap 'rm -rf "$native"' EXIT
target/debug/rae-cli denoise samples/random2026 -o "$native/out" >"$native/log" 2>&1 || {
  cat "$native/log"
  exit 1
}

echo "== the page in headless Chromium"
mkdir -p target/web-test
python3 tests/web/page_test.py --native "$native/out" --screenshot target/web-test/page.png "$@"
