"""Running a torch MLP's layers cheaply (P-DQN, MP-DQN and HybridPPO call small nets on small batches every step)."""

from __future__ import annotations

import torch as th
from torch import nn


def run_layers(layers: nn.Sequential, x: th.Tensor) -> th.Tensor:
    """
    ``layers(x)`` through each layer's ``forward``, without the module-call machinery (hooks), which costs more than
    the arithmetic of a small layer on a small batch. The result is the same tensor.
    """
    for layer in layers:
        x = layer.forward(x)
    return x
