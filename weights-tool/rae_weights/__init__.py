"""PyTorch side of rae: the network with the reference code's module names, the exporter to
rae's flat weights file, and the generator of the golden fixtures the Rust tests hold wgpu to."""

from .arch import Arch, INPUT_CHANNELS
from .model import RecurrentAE, prepare_input, finish_output

__all__ = ["Arch", "INPUT_CHANNELS", "RecurrentAE", "prepare_input", "finish_output"]
