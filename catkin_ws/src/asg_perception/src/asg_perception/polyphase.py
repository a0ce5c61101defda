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


def _conv(x: torch.Tensor, weight: torch.Tensor, bias: torch.Tensor) -> torch.Tensor:
    """2 x 2 convolution of `x` padded by one pixel: N x C x h x w -> N x C' x (h + 1) x (w + 1).
    fp32 goes to oneDNN always: torch's own choice sends small maps (the 8 x 8 bottleneck) to its
    im2col + BLAS path, 5x slower there, and a result then depends on a size heuristic."""
    if x.dtype == torch.float32 and torch.backends.mkldnn.is_available():
        return torch.mkldnn_convolution(x, weight, bias, (1, 1), (1, 1), (1, 1), 1)
    return F.conv2d(x, weight, bias, padding=1)  # float64 (the exactness tests), or no oneDNN


def phase_view(y: torch.Tensor, out_channels: int) -> torch.Tensor:
    """The four phases of a channels_last N x 4C x (h + 1) x (w + 1) result as one N x h x 2 x w x 2 x C
    view (no copy): element [n, i, a, j, b, c] is phase (a, b)'s output for pixel (2i + a, 2j + b),
    which sits at (i + a, j + b) in block 2a + b."""
    n, c4, h1, w1 = y.shape
    sn, sc, sh, sw = y.stride()
    c = out_channels
    if sc != 1 or c4 != 4 * c:
        raise ValueError(f"phase_view needs a channels_last N x 4C x h x w tensor, got {tuple(y.shape)}")
    return y.as_strided((n, h1 - 1, 2, w1 - 1, 2, c), (sn, sh, sh + 2 * c, sw, sw + c, 1))


def interleaved_view(out: torch.Tensor, channels: int) -> torch.Tensor:
    """The first `channels` channels of a channels_last N x C' x 2h x 2w tensor as the
    N x h x 2 x w x 2 x channels view that `phase_view` matches (no copy)."""
    n, _, hh, ww = out.shape
    sn, sc, sh, sw = out.stride()
    if sc != 1 or hh % 2 or ww % 2:
        raise ValueError(f"interleaved_view needs a channels_last tensor of even size, got {tuple(out.shape)}")
    return out.as_strided((n, hh // 2, 2, ww // 2, 2, channels), (sn, 2 * sh, sh, 2 * sw, sw, 1))


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

    def phases(self, x: torch.Tensor) -> torch.Tensor:
        """N x C_in x h x w -> the four phases, N x h x 2 x w x 2 x C_out (a view, `phase_view`),
        before the activation."""
        return phase_view(
            _conv(x.contiguous(memory_format=torch.channels_last), self.weight, self.bias), self.out_channels
        )

    def into(self, x: torch.Tensor, out: torch.Tensor) -> torch.Tensor:
        """Writes the upsampled result into the first C_out channels of `out` (N x C' x 2h x 2w,
        channels_last; a concatenation buffer): interleaving, activation and concatenation are one
        pass over memory."""
        dst = interleaved_view(out, self.out_channels)
        src = self.phases(x)
        if self.slope is None:
            dst.copy_(src)
        else:
            torch._C._nn.leaky_relu(src, self.slope, out=dst)
        return out

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        n, _, h, w = x.shape
        out = torch.empty((n, self.out_channels, 2 * h, 2 * w), dtype=x.dtype, memory_format=torch.channels_last)
        return self.into(x, out)


def first_max_of_three(logits: torch.Tensor) -> torch.Tensor:
    """argmax over the last dimension (size 3) as uint8, the first index on ties, as torch.argmax
    gives it, by two comparisons: 4x faster than argmax on the strided phase view. NaN logits (not
    produced by finite weights and inputs) would read as 0 here, not as argmax's NaN index."""
    l0, l1, l2 = logits.unbind(-1)
    labels = torch.gt(l1, l0).to(torch.uint8)
    labels.masked_fill_(torch.gt(l2, torch.maximum(l0, l1)), 2)
    return labels


class PolyphaseUNet(nn.Module):
    """`model.UNet` with its decoder and head in polyphase form; the encoder is the model's own."""

    def __init__(self, unet: nn.Module):
        super().__init__()
        self.down: nn.ModuleList = unet.down
        self.slope = unet.slope
        self.up = nn.ModuleList(UpConv(c, unet.slope) for c in unet.up)
        self.head = UpConv(unet.head)

    def features(self, x: torch.Tensor) -> torch.Tensor:
        """The head's input: encoder, then each decoder step written with its skip into one buffer."""
        skips: List[torch.Tensor] = []
        for conv in self.down:
            x = F.leaky_relu(conv(x), self.slope)
            skips.append(x)
        x = skips.pop()
        for up in self.up:
            skip = skips.pop()
            n, _, h, w = x.shape
            buf = torch.empty(
                (n, up.out_channels + skip.shape[1], 2 * h, 2 * w), dtype=x.dtype, memory_format=torch.channels_last
            )
            up.into(x, buf)
            buf[:, up.out_channels :].copy_(skip)
            x = buf
        return x

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """N x classes x H x W logits (channels_last)."""
        return self.head(self.features(x))

    def labels(self, x: torch.Tensor) -> torch.Tensor:
        """N x H x W uint8 labels, argmax of `forward`'s logits, taken on the head's phases before
        any interleaving (the labels are written once, at full resolution, in order)."""
        phases = self.head.phases(self.features(x))  # N x h x 2 x w x 2 x classes
        if phases.shape[-1] != 3:
            labels = phases.argmax(-1).to(torch.uint8)
        else:
            labels = first_max_of_three(phases)
        n, h, _, w, _ = labels.shape
        return labels.reshape(n, 2 * h, 2 * w)
