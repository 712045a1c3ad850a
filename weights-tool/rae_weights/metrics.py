"""Error metrics, defined exactly as rae-core's ``metrics.rs``: relMSE on radiance; PSNR and SSIM
on tonemapped images (x/(1+x), then the sRGB curve); temporal error on frame differences of
tonemapped images. Images are float arrays [H, W, 3] (numpy) of linear radiance.
"""

from __future__ import annotations

import numpy as np

#: relMSE's denominator guard: mean((x - r)^2 / (r^2 + RELMSE_EPS)).
RELMSE_EPS = 0.01


def tonemap(v: np.ndarray) -> np.ndarray:
    """Radiance -> display value in [0, 1): Reinhard x/(1+x), then sRGB encoding; NaN/Inf -> 0."""
    x = np.where(np.isfinite(v), np.maximum(v, 0.0), 0.0).astype(np.float64)
    t = x / (1.0 + x)
    return np.where(t <= 0.0031308, 12.92 * t, 1.055 * np.power(t, 1.0 / 2.4) - 0.055)


def relmse(x: np.ndarray, r: np.ndarray) -> float:
    """mean((x - r)^2 / (r^2 + 0.01)) over all values."""
    x64, r64 = x.astype(np.float64), r.astype(np.float64)
    return float(np.mean((x64 - r64) ** 2 / (r64**2 + RELMSE_EPS)))


def psnr(x: np.ndarray, r: np.ndarray) -> float:
    """PSNR in dB of the tonemapped images (peak 1)."""
    mse = float(np.mean((tonemap(x) - tonemap(r)) ** 2))
    return float("inf") if mse == 0 else -10.0 * np.log10(mse)


def _luma(img: np.ndarray) -> np.ndarray:
    t = tonemap(img)
    return 0.2126 * t[..., 0] + 0.7152 * t[..., 1] + 0.0722 * t[..., 2]


def _blur(v: np.ndarray) -> np.ndarray:
    """Separable 11-tap Gaussian (sigma 1.5), edges clamped."""
    k = np.exp(-(np.arange(-5, 6) ** 2) / (2 * 1.5**2))
    k /= k.sum()
    p = np.pad(v, 5, mode="edge")
    h, w = v.shape
    tmp = sum(k[i] * p[:, i : i + w] for i in range(11))
    return sum(k[i] * tmp[i : i + h, :] for i in range(11))


def ssim(x: np.ndarray, r: np.ndarray) -> float:
    """Mean SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5) of the tonemapped luminance."""
    a, b = _luma(x), _luma(r)
    ma, mb = _blur(a), _blur(b)
    va, vb, cov = _blur(a * a) - ma * ma, _blur(b * b) - mb * mb, _blur(a * b) - ma * mb
    c1, c2 = 0.01**2, 0.03**2
    s = ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2))
    return float(s.mean())


def temporal_error(x_prev: np.ndarray, x: np.ndarray, r_prev: np.ndarray, r: np.ndarray) -> float:
    """mean |(x_t - x_{t-1}) - (r_t - r_{t-1})| on tonemapped values."""
    return float(np.mean(np.abs((tonemap(x) - tonemap(x_prev)) - (tonemap(r) - tonemap(r_prev)))))


def sequence_metrics(outs: list[np.ndarray], refs: list[np.ndarray]) -> dict[str, float]:
    """Means over a sequence's frames: relmse, psnr, ssim, and temporal (over consecutive pairs)."""
    m = {
        "relmse": float(np.mean([relmse(o, r) for o, r in zip(outs, refs)])),
        "psnr": float(np.mean([psnr(o, r) for o, r in zip(outs, refs)])),
        "ssim": float(np.mean([ssim(o, r) for o, r in zip(outs, refs)])),
    }
    pairs = [temporal_error(outs[i - 1], outs[i], refs[i - 1], refs[i]) for i in range(1, len(outs))]
    m["temporal"] = float(np.mean(pairs)) if pairs else float("nan")
    return m


#: Shared test vectors (tests/fixtures/metrics_vectors.safetensors): rae-core's metrics.rs and
#: this module are both held to them.
VECTORS_FILE = "metrics_vectors.safetensors"


def shared_vectors(seed: int = 2026) -> dict[str, np.ndarray]:
    """Frame pairs of result and reference ([H, W, 3] float32: ``caseK.x_prev``, ``x``,
    ``r_prev``, ``r``) and their metrics by this module (``caseK.expected``: relmse, psnr, ssim,
    temporal, float64). Cases: noise around a smooth HDR image; values up to 1e4 with negatives
    and exact zeros; a result equal to its reference but for one pixel; a 1-pixel-high strip."""
    rng = np.random.default_rng(seed)
    cases = []
    h, w = 9, 13
    ramp = np.linspace(0.0, 3.0, h * w * 3, dtype=np.float32).reshape(h, w, 3)
    r_prev = ramp
    r = ramp * 1.1
    cases.append((r_prev + rng.normal(0, 0.3, ramp.shape), r + rng.normal(0, 0.3, ramp.shape), r_prev, r))
    wild = rng.uniform(-2.0, 1e4, (h, w, 3)) * (rng.uniform(size=(h, w, 3)) < 0.8)
    cases.append((wild, wild[::-1], np.abs(wild[:, ::-1]) * 0.5, np.abs(wild) * 0.5))
    one = r.copy()
    one[4, 6] = [50.0, 0.0, 2.0]
    cases.append((r_prev, one, r_prev, r))
    strip = rng.uniform(0.0, 4.0, (1, 17, 3))
    cases.append((strip, strip * 0.9 + 0.05, strip * 1.2, strip))
    out: dict[str, np.ndarray] = {}
    for k, (xp, x, rp, rr) in enumerate(cases):
        xp, x, rp, rr = (np.ascontiguousarray(a, dtype=np.float32) for a in (xp, x, rp, rr))
        out[f"case{k}.x_prev"], out[f"case{k}.x"], out[f"case{k}.r_prev"], out[f"case{k}.r"] = xp, x, rp, rr
        expected = [relmse(x, rr), psnr(x, rr), ssim(x, rr), temporal_error(xp, x, rp, rr)]
        out[f"case{k}.expected"] = np.array(expected, dtype=np.float64)
    return out
