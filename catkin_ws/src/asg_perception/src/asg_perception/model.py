"""The traversability U-Net (no rospy).

Five 3x3 stride-2 encoder convolutions (16, 32, 64, 128, 128 channels, LeakyReLU 0.2). Each
decoder step upsamples x2, applies a 3x3 convolution (128, 64, 32, 16 channels, LeakyReLU) and
concatenates the encoder feature map of that resolution; a final x2 upsample and 3x3 convolution
give the 3 class logits at the input resolution. 587,123 parameters, about 1.2 GFLOP for a
256 x 256 frame.

`unet(width)` scales every channel count by `width` (the shipped models before issue #24's lite
pair are width 1.0; the lite models are width 0.5: 8, 16, 32, 64, 64 channels, 147,259
parameters, about a quarter of the FLOP).
"""

from typing import List

import torch
from torch import nn
import torch.nn.functional as F

CLASSES = ("traversable", "non_traversable", "sky")


class UNet(nn.Module):
    def __init__(
        self,
        in_channels: int = 3,
        classes: int = 3,
        encoder: List[int] = (16, 32, 64, 128, 128),
        decoder: List[int] = (128, 64, 32, 16),
        slope: float = 0.2,
    ):
        super().__init__()
        if len(decoder) != len(encoder) - 1:
            raise ValueError("decoder needs one stage fewer than the encoder")
        self.slope = slope
        chans = [in_channels] + list(encoder)
        self.down = nn.ModuleList(
            nn.Conv2d(chans[i], chans[i + 1], 3, stride=2, padding=1) for i in range(len(encoder))
        )
        self.up = nn.ModuleList()
        c = encoder[-1]
        for k, out in enumerate(decoder):
            self.up.append(nn.Conv2d(c, out, 3, padding=1))
            c = out + encoder[-2 - k]  # after concatenating the skip of that resolution
        self.head = nn.Conv2d(c, classes, 3, padding=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """x: N x 3 x H x W in [0, 1] (H, W multiples of 32); returns N x classes x H x W logits."""
        skips = []
        for conv in self.down:
            x = F.leaky_relu(conv(x), self.slope)
            skips.append(x)
        x = skips.pop()
        for conv in self.up:
            x = F.interpolate(x, scale_factor=2.0, mode="nearest")
            x = F.leaky_relu(conv(x), self.slope)
            x = torch.cat([x, skips.pop()], dim=1)
        x = F.interpolate(x, scale_factor=2.0, mode="nearest")
        return self.head(x)


#: [channels] encoder widths at width 1.0 (the decoder mirrors all but the last)
BASE_ENCODER = (16, 32, 64, 128, 128)


def unet(width: float = 1.0) -> UNet:
    """The U-Net with every channel count scaled by `width` [fraction of BASE_ENCODER] (0 < width <= 4)."""
    if not 0.0 < float(width) <= 4.0:
        raise ValueError(f"U-Net width {width}: must be in (0, 4]")
    enc = [max(1, int(round(c * width))) for c in BASE_ENCODER]
    return UNet(encoder=enc, decoder=enc[-2::-1])


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
