"""Traversability perception of the stack under test: U-Net, datasets, training, evaluation and
fast inference (no rospy outside segmenter_node)."""

# The same oneDNN kernels on AMX and AVX512-BF16 CPUs (numerics.py): capped before torch creates
# its first kernel, whichever module of this package is imported first.
from . import numerics as _numerics  # noqa: E402

_numerics.pin()
