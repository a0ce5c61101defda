"""Fast single-frame inference of the U-Net on CPU (no rospy).

Backends, all giving the plain eager model's labels (checked by `asg_perception.benchmark` and
the tests):
- ``eager``: the model as trained, NCHW.
- ``channels_last``: NHWC memory layout, which oneDNN convolutions run without reorders, 2.3x
  faster than eager on one core (docs/benchmarks.md); the default until 2026-11-24 (issue #24)
  and again in issue #53 until ``polyphase`` replaced it: bit-identical closed-loop runs on every
  CPU class checked.
- ``frozen``: TorchScript, frozen and optimised for inference (conv/activation fusion), NHWC;
  measured no faster than eager with Debian's torch 1.13, kept for comparison.
- ``polyphase``: ``channels_last`` with the decoder and head in polyphase form
  (`asg_perception.polyphase`), the labels taken on the head's phases: the same function, about
  2x faster a frame; fp32, its logits within ~1e-5 of ``channels_last`` (as far as oneDNN's AVX2
  and AVX-512 kernels are from each other), its closed-loop runs those of ``channels_last`` bit
  for bit (the one fp32 reference set). The default since issue #53.
- ``bf16``: ``channels_last`` under torch's CPU autocast to bfloat16 (convolutions in bf16 with
  fp32 accumulation, argmax on the bf16 logits). Not bit-equal to eager: its labels agree on a
  measured share of pixels (docs/benchmarks.md), and it is deterministic run to run. Fast where
  the CPU has AVX512-BF16 (or AMX); elsewhere oneDNN emulates it, and the segmenter refuses it.
  The default from issue #24 to #53, a fast mode since: 1.9-2.0x channels_last per frame, 2,512
  against 1,743 Exp. 1 scenarios an hour on an AVX512-BF16 EPYC.
"""

import ctypes
import threading

import numpy as np
import torch

from .numerics import BACKENDS, DEFAULT_BACKEND  # noqa: F401 (the backends' one home; re-exported)
from .polyphase import PolyphaseUNet
from .train import load_model


def cap_openblas(threads: int) -> bool:
    """Caps OpenBLAS's own thread pool at `threads`; True if an OpenBLAS was found. torch runs
    some convolutions as im2col + sgemm in the BLAS (the polyphase head's 2x2 one), and the pthread
    OpenBLAS of Debian keeps one server thread a core that busy-waits on sched_yield after every
    call: with frames arriving in gaps it burnt 21.5 ms of CPU a frame beside 11.5 ms of inference
    (issue #53). OpenBLAS splits a product over its output blocks, so the sums do not change."""
    found = False
    for name in ("libopenblas.so.0", "libblas.so.3"):
        try:
            getattr(ctypes.CDLL(name), "openblas_set_num_threads")(int(threads))
            found = True
        except (OSError, AttributeError):  # not installed, or a BLAS that is not OpenBLAS
            pass
    return found


class Segmenter:
    """Labels (H x W uint8: 0 traversable, 1 non-traversable, 2 sky) for RGB frames."""

    def __init__(
        self, model_path: str, backend: str = DEFAULT_BACKEND, threads: int = 1, height: int = 256, width: int = 256
    ):
        if backend not in BACKENDS:
            raise ValueError(f"backend {backend!r}: one of {', '.join(BACKENDS)}")
        if height % 32 or width % 32:
            raise ValueError(f"frame size {width}x{height}: both must be multiples of 32")
        torch.set_num_threads(threads)
        cap_openblas(threads)
        self.threads, self._thread = threads, threading.get_ident()
        self.backend = backend
        self.shape = (height, width)
        model = load_model(model_path)
        self.channels_last = backend != "eager"
        if self.channels_last:
            model = model.to(memory_format=torch.channels_last)
        if backend == "frozen":
            example = self._input(np.zeros((height, width, 3), np.uint8))
            with torch.no_grad():
                traced = torch.jit.trace(model, example)
                model = torch.jit.optimize_for_inference(torch.jit.freeze(traced))
        if backend == "polyphase":
            model = PolyphaseUNet(model)
        self.model = model
        self.bf16 = backend == "bf16"
        self(np.zeros((height, width, 3), np.uint8))  # warm up (oneDNN primitive caches)

    def _input(self, rgb: np.ndarray) -> torch.Tensor:
        if not rgb.flags.writeable:  # a message buffer: torch wants memory it may write
            rgb = rgb.copy()
        x = torch.from_numpy(rgb).permute(2, 0, 1).unsqueeze(0).float().div_(255.0)
        return x.contiguous(memory_format=torch.channels_last) if self.channels_last else x.contiguous()

    def __call__(self, rgb: np.ndarray) -> np.ndarray:
        if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"expected H x W x 3 uint8 RGB, got {rgb.dtype} {rgb.shape}")
        if rgb.shape[:2] != self.shape:
            raise ValueError(
                f"frame is {rgb.shape[1]}x{rgb.shape[0]}, the segmenter was made "
                f"for {self.shape[1]}x{self.shape[0]}"
            )
        if threading.get_ident() != self._thread:
            # OpenMP's thread count is per thread: one that never set it (the segmenter node's
            # callback thread) forks teams of every core, whose spare threads spin on a shared CPU
            # (issue #53: a third of a core per segmenter in a campaign), and the recorded
            # `threads` would not be what ran.
            torch.set_num_threads(self.threads)
            self._thread = threading.get_ident()
        with torch.no_grad(), torch.autocast("cpu", dtype=torch.bfloat16, enabled=self.bf16):
            if isinstance(self.model, PolyphaseUNet):  # labels from the head's phases, no logit image
                return self.model.labels(self._input(rgb))[0].numpy()
            logits = self.model(self._input(rgb))
        return logits[0].argmax(0).to(torch.uint8).numpy()

    def batch(self, rgb: np.ndarray) -> np.ndarray:
        """Labels (N x H x W uint8) for N RGB frames, one at a time as the node runs them."""
        return np.stack([self(f) for f in rgb]) if len(rgb) else np.zeros((0, *self.shape), np.uint8)
