"""The architecture a weights file declares: the one description both runtimes build from.

It is stored as JSON under the key ``rae.arch`` in the safetensors ``__metadata__``; rae-core's
``model::Arch`` reads the same fields and rejects what it does not know.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

#: Channels each input buffer contributes to the network input, by name.
INPUT_CHANNELS: dict[str, int] = {"color": 3, "albedo": 3, "normal": 3, "depth": 1, "roughness": 1}

FORMAT = "rae"
VERSION = 1


@dataclass
class Arch:
    """Architecture of a recurrent denoising autoencoder (defaults: the reference code's)."""

    #: Buffers packed into the network input, in channel order (color first, always).
    inputs: list[str] = field(default_factory=lambda: ["color", "normal", "depth", "roughness"])
    #: Divide color by (albedo + albedo_eps) before the network and multiply back after.
    demodulate: bool = True
    albedo_eps: float = 1e-3
    #: HDR transfer function on the (demodulated) color: "log1p" or "none" (what rae-core runs);
    #: "pow0.2" and "pu21" for the training comparison only (``transfer``).
    transfer: str = "log1p"
    #: Widths of the encoder blocks d1..dN; the bottleneck runs at 1/2^N resolution.
    encoder: list[int] = field(default_factory=lambda: [32, 43, 57, 76, 101])
    bottleneck: int = 101
    #: "pooled": decoder concatenates pooled encoder features before upsampling (reference code);
    #: "prepool": features before pooling are concatenated after upsampling (the paper).
    skip: str = "pooled"
    #: Activation after the last convolution: "lrelu" (reference code) or "linear" (paper).
    output_activation: str = "lrelu"
    out_channels: int = 3
    negative_slope: float = 0.1

    def __post_init__(self) -> None:
        self.validate()

    @property
    def in_channels(self) -> int:
        """Channels of the packed network input."""
        return sum(INPUT_CHANNELS[name] for name in self.inputs)

    @property
    def levels(self) -> int:
        return len(self.encoder)

    @property
    def required_buffers(self) -> list[str]:
        """Buffers a frame must carry: the network inputs plus albedo when demodulating."""
        need = list(self.inputs)
        if self.demodulate and "albedo" not in need:
            need.append("albedo")
        return need

    def decoder_widths(self) -> list[int]:
        """Output widths of u1..uN (index 0 is u1)."""
        return [self.out_channels] + list(self.encoder[:-1])

    def validate(self) -> None:
        unknown = [n for n in self.inputs if n not in INPUT_CHANNELS]
        if unknown:
            raise ValueError(f"unknown input buffer(s) {unknown}; known: {list(INPUT_CHANNELS)}")
        if not self.inputs or self.inputs[0] != "color":
            raise ValueError("inputs must start with 'color'")
        if len(set(self.inputs)) != len(self.inputs):
            raise ValueError(f"duplicate input buffer in {self.inputs}")
        if self.transfer not in ("log1p", "none", "pow0.2", "pu21"):
            raise ValueError(f"unknown transfer {self.transfer!r}")
        if self.skip not in ("pooled", "prepool"):
            raise ValueError(f"unknown skip variant {self.skip!r}")
        if self.output_activation not in ("lrelu", "linear"):
            raise ValueError(f"unknown output activation {self.output_activation!r}")
        if not 1 <= len(self.encoder) <= 8 or min(self.encoder) < 1 or self.bottleneck < 1:
            raise ValueError(f"bad encoder widths {self.encoder} / bottleneck {self.bottleneck}")
        if self.albedo_eps <= 0:
            raise ValueError("albedo_eps must be positive")

    def to_json(self) -> str:
        d = {"format": FORMAT, "version": VERSION, **asdict(self)}
        return json.dumps(d, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "Arch":
        d = json.loads(text)
        if d.pop("format", None) != FORMAT or d.pop("version", None) != VERSION:
            raise ValueError("not a rae v1 architecture")
        return cls(**d)

    def tensor_shapes(self) -> dict[str, tuple[int, ...]]:
        """Every tensor the weights file must hold, with its shape (PyTorch names, OIHW)."""
        shapes: dict[str, tuple[int, ...]] = {}

        def conv(name: str, cin: int, cout: int) -> None:
            shapes[f"{name}.weight"] = (cout, cin, 3, 3)
            shapes[f"{name}.bias"] = (cout,)

        cin = self.in_channels
        for k, w in enumerate(self.encoder, start=1):
            conv(f"d{k}.l1.0", cin, w)
            conv(f"d{k}.l2.0", 2 * w, w)
            conv(f"d{k}.l2.2", w, w)
            cin = w
        b = self.bottleneck
        conv("bottleneck.l1.0", cin, b)
        conv("bottleneck.l2.0", 2 * b, b)
        conv("bottleneck.l2.2", b, b)
        prev = b
        dec = self.decoder_widths()
        for k in range(self.levels, 0, -1):
            out = dec[k - 1]
            conv(f"u{k}.l1.1", prev + self.encoder[k - 1], out)
            conv(f"u{k}.l1.3", out, out)
            prev = out
        return shapes
