"""The agent's BLAS kernel, the same on every CPU (issue #68; no ROS, no numpy at import).

The search methods' arithmetic (TD3's networks in torch, the surrogate's regression in numpy and
scikit-learn) runs on Debian's OpenBLAS, which picks its kernels by the CPU it finds: SkylakeX on
an AVX-512 EPYC or Xeon, Haswell on an AVX2-only one, others elsewhere. Kernels sum in different
orders, so the same seeded campaign drifts apart on two CPU classes once a method's decisions
depend on such sums (measured: TD3-PER-ASP, seed 0, with the in-process stand-in pool, proposes
the same first 116 layouts under the SkylakeX and Haswell kernels and a different 117th, the
first after its warm-up; scenes and their runs are not affected, the stack's numerics are
asg_perception's). `pin_blas` sets OpenBLAS's kernel to AGENT_KERNEL (AVX2, which every CPU class
of the project has) before OpenBLAS is loaded, so a seeded campaign proposes the same scenes on
each; `ASG_AGENT_BLAS=native` leaves OpenBLAS's own choice. `blas_identity` is what a campaign
records of it.
"""

import os

#: OpenBLAS's kernel for the agent (OPENBLAS_CORETYPE): AVX2, on every CPU class of the project
AGENT_KERNEL = "Haswell"


def _has_avx2() -> bool:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            return any(line.startswith("flags") and " avx2" in line for line in f)
    except OSError:
        return False


def pin_blas() -> str:
    """Sets OPENBLAS_CORETYPE to AGENT_KERNEL for this process (call it before numpy or torch is
    imported), unless ASG_AGENT_BLAS=native or the CPU lacks AVX2; returns the kernel set ("")."""
    if os.environ.get("ASG_AGENT_BLAS", "") == "native" or not _has_avx2():
        return ""
    os.environ["OPENBLAS_CORETYPE"] = AGENT_KERNEL
    return AGENT_KERNEL


def blas_identity() -> str:
    """The loaded OpenBLAS and its kernel, e.g. "openblas 0.3.21 Haswell" ("" when none is seen)."""
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return ""
    for lib in threadpool_info():
        if lib.get("internal_api") == "openblas":
            return f"openblas {lib.get('version')} {lib.get('architecture')}"
    return ""
