"""The traversability U-Net (no rospy).

Five 3x3 stride-2 encoder convolutions (16, 32, 64, 128, 128 channels, LeakyReLU 0.2). Each
decoder step upsamples x2, applies a 3x3 convolution (128, 64, 32, 16 channels, LeakyReLU) and
concatenates the encoder feature map of that resolution; a final x2 upsample and 3x3 convolution
give the 3 class logits at the input resolution. 587,123 parameters, about 1.2 GFLOP for a
256 x 256 frame.
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


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
