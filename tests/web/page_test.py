"""The page (crates/rae-web) in a real browser, held to PyTorch and to native rae-core.

Serves the built site (scripts/web.sh --build-only) on a free localhost port, opens it in
headless Chromium (WebGPU through SwiftShader, with WebGPU's default limits), and checks:

1. a picked file that is not an EXR gets a message naming it, and the page keeps working, and a
   browser without WebGPU gets a message that says so;
2. every golden fixture of the manifest matches PyTorch's output in the page within the golden
   tolerance (|wgpu - torch| <= 1e-4 * max(1, |torch|));
3. the sample sequence, denoised in the page frame by frame with its hidden state carried and
   reprojected, matches native rae-core (rae-cli on this machine's device, EXRs in --native)
   within the same tolerance, and picked through the file picker gives the same errors.

Writes a screenshot of the page after the sample (--screenshot) and prints, last, one line with
the largest differences and the page's ms per frame.
"""

from __future__ import annotations

import argparse
import base64
import functools
import http.server
import pathlib
import statistics
import sys
import threading

import numpy as np
import OpenEXR
from playwright.sync_api import sync_playwright

TOLERANCE = 1e-4


def serve(site: pathlib.Path) -> http.server.ThreadingHTTPServer:
    """A quiet static server of `site` on a free port, in a thread."""


    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, format: str, *args: object) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def read_rgb(path: pathlib.Path) -> np.ndarray:
    """An RGB EXR as float32, interleaved (height, width, 3)."""
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, dtype=np.float32)
        return np.stack([np.asarray(channels[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)


def ratio(actual: np.ndarray, expected: np.ndarray) -> float:
    """Largest |actual - expected| / (TOLERANCE * max(1, |expected|)); inf where not finite."""
    err = np.abs(actual.astype(np.float64) - expected.astype(np.float64))
    r = err / (TOLERANCE * np.maximum(1.0, np.abs(expected.astype(np.float64))))
    return float(np.max(np.where(np.isfinite(r), r, np.inf)))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--site", type=pathlib.Path, default=pathlib.Path("target/web"))
    ap.add_argument("--native", type=pathlib.Path, required=True, help="rae-cli's denoised_NNNN.exr of the sample")
    ap.add_argument("--screenshot", type=pathlib.Path, default=pathlib.Path("target/web-test/page.png"))
    ap.add_argument("--browser", default="/usr/bin/chromium")
    args = ap.parse_args()

    server = serve(args.site)
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html?default-limits"
    failures: list[str] = []
    console: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=args.browser, args=["--no-sandbox", "--enable-unsafe-webgpu"])
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.on("console", lambda m: console.append(f"{m.type}: {m.text}"))
        page.on("pageerror", lambda e: console.append(f"page error: {e}"))
        page.goto(url)
        page.wait_for_function(
            "document.body.dataset.ready === '1' || !document.getElementById('message').hidden", timeout=60_000
        )
        if not page.is_hidden("#message"):
            print("\n".join(console), file=sys.stderr)
            print(f"the page did not start: {page.inner_text('#message')}", file=sys.stderr)
            return 1
        adapter = page.inner_text("#adapter")
        print(adapter)

        # 1. A picked file that does not read: a message naming it.
        page.set_input_files("#pick", files=[{"name": "color_0001.exr", "mimeType": "image/x-exr", "buffer": b"not an EXR"}])
        page.wait_for_function("!document.getElementById('message').hidden", timeout=60_000)
        shown = page.inner_text("#message")
        print(f"bad file: {shown.splitlines()[0]}")
        if "color_0001.exr" not in shown:
            failures.append(f"the message for an unreadable file does not name it: {shown!r}")

        # 2 and 3. Golden fixtures and the sample (after the error: the page keeps working).
        result = page.evaluate("raeTest()")

        # The sample again, picked as a user picks files: the same frames, the same errors.
        sample = args.site / "samples" / "random2026"
        page.set_input_files("#pick", files=sorted(str(f) for f in sample.iterdir()))
        page.wait_for_function(
            "document.getElementById('status').textContent.startsWith('56 files: 8 frames')"
            " || !document.getElementById('message').hidden",
            timeout=300_000,
        )
        if not page.is_hidden("#message"):
            failures.append(f"the picked sample: {page.inner_text('#message')}")
        rows = page.eval_on_selector_all("#frames tbody tr", "rows => rows.map(r => r.cells[3].textContent)")
        want = [f"{f['psnrOut']:.2f}" for f in result["sample"]]
        print(f"picked sample: PSNR out {', '.join(rows)}")
        if rows != want:
            failures.append(f"the picked sample's PSNR {rows} differs from the fetched one's {want}")
        page.screenshot(path=str(args.screenshot), full_page=True)

        # A browser without WebGPU: a message that says so.
        bare = browser.new_page()
        bare.add_init_script("Object.defineProperty(Navigator.prototype, 'gpu', { get: () => undefined });")
        bare.goto(url)
        bare.wait_for_function("!document.getElementById('message').hidden", timeout=60_000)
        shown = bare.inner_text("#message")
        print(f"no WebGPU: {shown}")
        if "WebGPU" not in shown:
            failures.append(f"a browser without WebGPU gets no message that says so: {shown!r}")
        browser.close()
    server.shutdown()

    worst_golden = 0.0
    for g in result["golden"]:
        print(f"golden {g['file']}: {g['frames']} frames, worst {g['worst']:.3f} of the tolerance, largest |difference| {g['maxAbs']:.2e}")
        worst_golden = max(worst_golden, g["worst"])
        if not g["worst"] <= 1.0:
            failures.append(f"{g['file']}: {g['worst']:.3f} of the golden tolerance")
    worst_native, largest_abs = 0.0, 0.0
    for f in result["sample"]:
        page_out = np.frombuffer(base64.b64decode(f["output"]), dtype="<f4")
        native_path = args.native / f"denoised_{f['number']:04d}.exr"
        native = read_rgb(native_path).reshape(-1)
        if native.shape != page_out.shape:
            failures.append(f"frame {f['number']}: the page gave {page_out.size} values, {native_path} has {native.size}")
            continue
        r = ratio(page_out, native)
        worst_native = max(worst_native, r)
        largest_abs = max(largest_abs, float(np.max(np.abs(page_out - native))))
        print(f"sample frame {f['number']}: {f['ms']:.1f} ms, PSNR {f['psnrIn']:.2f} -> {f['psnrOut']:.2f} dB, {r:.3f} of the tolerance against native")
        if not r <= 1.0:
            failures.append(f"sample frame {f['number']}: {r:.3f} of the tolerance against native rae-core")
    for message in failures:
        print(f"FAILED: {message}", file=sys.stderr)
    if failures:
        print("\n".join(console[-20:]), file=sys.stderr)
    ms = [f["ms"] for f in result["sample"]]
    print(
        f"web-test: {'FAILED' if failures else 'passed'}: golden worst {worst_golden:.3f} of the tolerance "
        f"({len(result['golden'])} fixtures); sample vs native largest |difference| {largest_abs:.2e} "
        f"({worst_native:.3f} of the tolerance); {statistics.median(ms[1:] or ms):.0f} ms a frame in the page "
        f"(median after the first; {ms[0]:.0f} ms the first) in headless Chromium, SwiftShader"
    )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
