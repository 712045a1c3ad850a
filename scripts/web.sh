#!/usr/bin/env bash
# The page (crates/rae-web): builds rae-web for wasm32, generates its JavaScript bindings with
# the wasm-bindgen CLI of the version Cargo.lock pins (installed from crates.io if missing;
# its lockfile pins a webpki-roots that crates.io's index here lacks, so not --locked),
# assembles the site in target/web (the page, the shipped models, the sample sequence and the
# golden fixtures the test runs, with a manifest.json listing them) and serves it on
# http://127.0.0.1:${PORT:-8000}/.
#   bash scripts/web.sh                 build and serve
#   bash scripts/web.sh --build-only    build only (scripts/web-test.sh)
set -euo pipefail
cd "$(dirname "$0")/.."

out=target/web
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print }' Cargo.lock)

rustup target add wasm32-unknown-unknown >/dev/null 2>&1 || rustup target add wasm32-unknown-unknown
if [ "$(wasm-bindgen --version 2>/dev/null)" != "wasm-bindgen $version" ]; then
  # Unoptimised and the one binary the build runs: 0.4x the install time of the release build
  # of all three, and its output is the same (0.7 s for the page's module instead of 0.15).
  echo "== installing wasm-bindgen-cli $version (crates.io; about a minute)"
  cargo install -q wasm-bindgen-cli --version "$version" --debug --bin wasm-bindgen
fi

echo "== building the page: rae-web for wasm32-unknown-unknown, wasm-bindgen $version"
cargo build --locked -q --release -p rae-web --target wasm32-unknown-unknown
rm -rf "$out.partial"
mkdir -p "$out.partial/pkg" "$out.partial/models" "$out.partial/fixtures" "$out.partial/samples"
wasm-bindgen --target web --no-typescript --out-dir "$out.partial/pkg" target/wasm32-unknown-unknown/release/rae_web.wasm
cp crates/rae-web/www/* "$out.partial/"
# The shipped models in rae-cli's order of preference (the page picks the first that fits).
models="rae-default rae-color-albedo-normal rae-color"
for m in $models; do cp "models/$m.safetensors" "$out.partial/models/"; done
cp -r samples/random2026 "$out.partial/samples/"
cp tests/fixtures/golden_*.safetensors tests/fixtures/weights_*.safetensors "$out.partial/fixtures/"
python3 - "$out.partial" $models <<'EOF'
import json, pathlib, sys
from safetensors import safe_open

site, models = pathlib.Path(sys.argv[1]), sys.argv[2:]
golden = []
for f in sorted((site / "fixtures").glob("golden_*.safetensors")):
    with safe_open(str(f), "np") as g:
        weights = json.loads(g.metadata()["rae.golden"])["weights"]
    golden.append({"file": f"fixtures/{f.name}", "weights": f"fixtures/{weights}"})
sample = site / "samples" / "random2026"
manifest = {
    "models": [{"name": m, "file": f"models/{m}.safetensors"} for m in models],
    "sample": {"name": "random2026", "path": "samples/random2026", "files": sorted(p.name for p in sample.iterdir())},
    "golden": golden,
}
(site / "manifest.json").write_text(json.dumps(manifest, indent=1))
EOF
rm -rf "$out"
mv "$out.partial" "$out"
echo "== the page is in $out"

if [ "${1:-}" != "--build-only" ]; then
  port="${PORT:-8000}"
  echo "== serving http://127.0.0.1:$port/ (Ctrl-C stops)"
  exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$out"
fi
