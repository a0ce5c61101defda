"""The U-Net's decoder in polyphase form: the same function, 1.9x faster a frame on one core (no rospy).

Each decoder step of `model.UNet` (and its head) upsamples x2 by nearest neighbour and then applies
a 3x3 convolution (padding 1). Every output pixel (2i + a, 2j + b) of that pair sees only a 2 x 2
window of the low-resolution map, with taps that fold together the 3x3 weights falling on the same
low-resolution pixel:

    phase a = 0 (even rows): low rows (i - 1, i)   with row weights (w0, w1 + w2)
    phase a = 1 (odd rows):  low rows (i, i + 1)   with row weights (w0 + w1, w2)

and the same for columns (b). So the four phases are one 2 x 2 convolution with 4 x C_out outputs
on the low-resolution map padded by one pixel ((h + 1) x (w + 1) outputs), phase (a, b) read at
offset (a, b), then interleaved. It does 4/9 of the upsampled convolution's multiply-adds, never
builds the upsampled map, and gives the 3-class head 12 output channels instead of 3 (oneDNN
vectorises over output channels, so a 3-channel head at full resolution leaves most lanes idle:
36 % of the U-Net's convolution time for 9 % of its FLOP, docs/benchmarks.md).

It is the same function in exact arithmetic; in fp32 the folded weights and the changed order of
the sums move the logits by ~1e-5, the size of what moving between oneDNN's AVX2 and AVX-512 kernels
does to `channels_last` itself. How often a label then differs, and whether closed-loop runs stay
bit for bit the stored ones: docs/benchmarks.md, "The polyphase decoder".
"""

from typing import List, Tuple

import torch
import torch.nn.functional as F
from torch import nn

#: the four output phases (row parity a, column parity b), in the order of the output blocks
PHASES: Tuple[Tuple[int, int], ...] = ((0, 0), (0, 1), (1, 0), (1, 1))


def _fold(w: torch.Tensor, dim: int, phase: int) -> torch.Tensor:
    """The 3 taps of `w` along `dim` folded into the 2 that phase `phase` sees."""
    t0, t1, t2 = w.unbind(dim)
    return torch.stack((t0, t1 + t2) if phase == 0 else (t0 + t1, t2), dim)


def phase_kernel(weight: torch.Tensor) -> torch.Tensor:
    """(4 C_out) x C_in x 2 x 2 kernel equal to nearest-x2 upsampling then `weight` (C_out x C_in x
    3 x 3, padding 1), its output blocks in PHASES order."""
    if weight.dim() != 4 or weight.shape[2:] != (3, 3):
        raise ValueError(f"expected a C_out x C_in x 3 x 3 kernel, got {tuple(weight.shape)}")
    return torch.cat([_fold(_fold(weight, 2, a), 3, b) for a, b in PHASES])


class UpConv(nn.Module):
    """nearest x2 upsampling then a 3x3 convolution (padding 1) [then LeakyReLU], in polyphase form."""

    def __init__(self, conv: nn.Conv2d, slope: float = None):
        super().__init__()
        if conv.kernel_size != (3, 3) or conv.stride != (1, 1) or conv.padding != (1, 1) or conv.groups != 1:
            raise ValueError(f"{conv}: polyphase form needs a 3x3, stride 1, padding 1 convolution")
        w = conv.weight.detach()
        self.weight = nn.Parameter(phase_kernel(w).contiguous(memory_format=torch.channels_last), False)
        self.bias = nn.Parameter(conv.bias.detach().repeat(4), False)
        self.out_channels = w.shape[0]
        self.slope = slope

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        n, _, h, w = x.shape
        y = F.conv2d(F.pad(x, (1, 1, 1, 1)), self.weight, self.bias)  # N x 4C x (h+1) x (w+1)
        if self.slope is not None:
            y = F.leaky_relu(y, self.slope)
        c = self.out_channels
        out = torch.empty((n, c, 2 * h, 2 * w), dtype=y.dtype).contiguous(memory_format=torch.channels_last)
        for k, (a, b) in enumerate(PHASES):
            out[:, :, a::2, b::2] = y[:, k * c : (k + 1) * c, a : a + h, b : b + w]
        return out


class PolyphaseUNet(nn.Module):
    """`model.UNet` with its decoder and head in polyphase form; the encoder is the model's own."""

    def __init__(self, unet: nn.Module):
        super().__init__()
        self.down: nn.ModuleList = unet.down
        self.slope = unet.slope
        self.up = nn.ModuleList(UpConv(c, unet.slope) for c in unet.up)
        self.head = UpConv(unet.head)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        skips: List[torch.Tensor] = []
        for conv in self.down:
            x = F.leaky_relu(conv(x), self.slope)
            skips.append(x)
        x = skips.pop()
        for up in self.up:
            x = torch.cat([up(x), skips.pop()], dim=1)
        return self.head(x)
