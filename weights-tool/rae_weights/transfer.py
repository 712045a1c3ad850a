"""HDR transfer functions on (demodulated) color, the candidates issue 5 compares by training.

``log1p`` ships (rae-core's prep.wgsl and output.wgsl implement it); ``pow0.2`` and ``pu21`` exist
here for the measurement that chose it (``docs/MODELS.md``, "Transfer function"), and ``none``
for the linear variant. Each maps radiance >= 0 to the network's space and back exactly:
``decode(encode(x)) == x`` up to float rounding.

- ``log1p``: log(1 + x).
- ``pow0.2``: (x + e)^0.2 - e^0.2 with e = 1e-4 (finite slope at 0).
- ``pu21``: PU21 (Mantiuk & Azimi 2021, "banding with glare" parameters) of 100 x + 0.005 cd/m^2
  (radiance 1 as 100 cd/m^2, 0 as PU21's floor), shifted to 0 at 0 and scaled to 1 at x = 1.
"""

from __future__ import annotations

import math

import torch

TRANSFERS = ("log1p", "none", "pow0.2", "pu21")

_POW_EPS = 1e-4
_PU = (0.353487901, 0.3734658629, 8.277049286e-05, 0.9062562627, 0.09150303166, 0.9099517204, 596.3148142)
_PU_Y0, _PU_SCALE = 0.005, 100.0


def _pu21(y: torch.Tensor) -> torch.Tensor:
    p = _PU
    z = y.clamp(min=_PU_Y0) ** p[3]
    return p[6] * (((p[0] + p[1] * z) / (1 + p[2] * z)) ** p[4] - p[5])


def _pu21_inv(v: torch.Tensor) -> torch.Tensor:
    p = _PU
    u = (v / p[6] + p[5]).clamp(min=1e-12) ** (1 / p[4])
    z = ((u - p[0]) / (p[1] - p[2] * u)).clamp(min=0.0)
    return z ** (1 / p[3])


def _pu_consts() -> tuple[float, float]:
    lo = float(_pu21(torch.tensor(_PU_Y0, dtype=torch.float64)))
    hi = float(_pu21(torch.tensor(_PU_Y0 + _PU_SCALE, dtype=torch.float64)))
    return lo, hi - lo


_PU_LO, _PU_RANGE = _pu_consts()


def encode(name: str, x: torch.Tensor) -> torch.Tensor:
    """Radiance (>= 0) -> network space."""
    if name == "log1p":
        return torch.log1p(x)
    if name == "pow0.2":
        return (x + _POW_EPS) ** 0.2 - _POW_EPS**0.2
    if name == "pu21":
        return (_pu21(_PU_SCALE * x + _PU_Y0) - _PU_LO) / _PU_RANGE
    return x


def decode(name: str, y: torch.Tensor) -> torch.Tensor:
    """Network space -> radiance (the inverse of ``encode`` on its range)."""
    if name == "log1p":
        return torch.expm1(y)
    if name == "pow0.2":
        return (y + _POW_EPS**0.2).clamp(min=0.0) ** 5 - _POW_EPS
    if name == "pu21":
        return ((_pu21_inv(y * _PU_RANGE + _PU_LO) - _PU_Y0) / _PU_SCALE).clamp(min=0.0)
    return y


def limit(name: str, in_max: torch.Tensor, gain: float, radiance_max: float, log_max: float) -> torch.Tensor:
    """Upper clamp of the network output: encode(gain * decode(in_max)), kept finite."""
    if name == "log1p":
        return torch.log1p(gain * torch.expm1(in_max)).clamp(max=log_max)
    if name == "none":
        return (gain * in_max).clamp(max=radiance_max)
    return encode(name, (gain * decode(name, in_max)).clamp(max=radiance_max))


assert math.isfinite(_PU_RANGE) and _PU_RANGE > 0
