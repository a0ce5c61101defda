"""What decides the U-Net's numerics on a CPU, pinned and recorded (no rospy; issue #36).

oneDNN, under torch, picks its convolution kernels by the CPU's instruction set. For bf16, an
Intel Xeon with AMX runs AMX kernels and a CPU with AVX512-BF16 (but no AMX) runs AVX-512 ones:
the labels differ in a few pixels, and a run recorded on one does not replay on the other. So
the segmenter caps oneDNN at ISA_CAP (the environment variable ONEDNN_MAX_CPU_ISA, and its older
name DNNL_MAX_CPU_ISA, set before oneDNN creates its first kernel) and records which kernels it
can then use: the *effective ISA*, the cap or the CPU's best below it. Two machines with the same
effective ISA, thread count and torch give the same labels; `replay` refuses, before it runs, a
stored run whose effective ISA this machine cannot reach, saying why.

A user may set ONEDNN_MAX_CPU_ISA themselves; the effective ISA recorded is then theirs.
"""

import os
from typing import Iterable, Optional

#: oneDNN's ISA names, lowest first (the subset that decides x86-64 convolution kernels)
ISA_ORDER = (
    "SSE41",
    "AVX",
    "AVX2",
    "AVX2_VNNI",
    "AVX512_CORE",
    "AVX512_CORE_VNNI",
    "AVX512_CORE_BF16",
    "AVX512_CORE_FP16",
    "AVX512_CORE_AMX",
)
#: the highest ISA the segmenter lets oneDNN use: AVX512-BF16, the kernels the stored references
#: were recorded with (tests/reference); AMX machines then run the same kernels.
ISA_CAP = "AVX512_CORE_BF16"
ENV = ("ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA")
#: the U-Net inference backends (asg_perception.inference.Segmenter), and the shipped one: the
#: one home of the default, read by the segmenter node (an empty ~backend), the launch files (an
#: empty unet_backend), asg_agent's experiments (a file without unet_backend) and the tests. Here,
#: in a module without torch, so that asg_agent reads it without loading the U-Net's code.
#: Since issue #53 the default is fp32: first channels_last, then polyphase (channels_last with the
#: decoder in polyphase form, the same function, 2.2x faster a frame). Their closed-loop runs are
#: bit-identical to each other and on every CPU class the project has met (docs/benchmarks.md,
#: "CPU classes" and "The polyphase decoder"), so one stored reference set serves them all; bf16
#: is a fast mode a user asks for, on CPUs that run it natively.
BACKENDS = ("eager", "channels_last", "frozen", "bf16", "polyphase")
DEFAULT_BACKEND = "polyphase"
#: fp32 backends whose closed-loop runs replay each other's bit for bit (measured: the stored
#: reference runs and seeded 120-scenario campaigns, docs/benchmarks.md "The polyphase decoder"):
#: a run recorded on one replays on the other, as across FP32_PORTABLE_ISAS
FP32_PORTABLE_BACKENDS = ("channels_last", "polyphase")
#: backends whose convolutions run in bf16 (the others run fp32, whose kernels VNNI, BF16 and AMX
#: do not change: their numerics are those of FP32_TOP on any CPU at or above it)
BF16_BACKENDS = ("bf16",)
FP32_TOP = "AVX512_CORE"

# /proc/cpuinfo flags each ISA needs (all of them)
_NEEDS = {
    "SSE41": ("sse4_1",),
    "AVX": ("avx",),
    "AVX2": ("avx2",),
    "AVX2_VNNI": ("avx2", "avx_vnni"),
    "AVX512_CORE": ("avx512f", "avx512bw", "avx512vl", "avx512dq"),
    "AVX512_CORE_VNNI": ("avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512_vnni"),
    "AVX512_CORE_BF16": ("avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512_vnni", "avx512_bf16"),
    "AVX512_CORE_FP16": ("avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512_vnni", "avx512_bf16", "avx512_fp16"),
    "AVX512_CORE_AMX": ("avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512_vnni", "avx512_bf16", "amx_bf16"),
}


def cpu_flags(path: str = "/proc/cpuinfo") -> frozenset:
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.startswith("flags"):
                    return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


def best_isa(flags: Iterable[str]) -> str:
    """The highest ISA of ISA_ORDER the CPU has ("" when not even SSE4.1: not x86-64)."""
    flags = set(flags)
    best = ""
    for isa in ISA_ORDER:
        if all(f in flags for f in _NEEDS[isa]):
            best = isa
    return best


def effective_isa(flags: Iterable[str], cap: Optional[str] = None) -> str:
    """The kernels oneDNN can use: the CPU's best ISA, capped at `cap` (default: the
    environment's ONEDNN_MAX_CPU_ISA, else ISA_CAP)."""
    cap = (cap or os.environ.get(ENV[0]) or os.environ.get(ENV[1]) or ISA_CAP).upper()
    if cap == "ALL":  # oneDNN's own word for no cap
        cap = ISA_ORDER[-1]
    if cap not in ISA_ORDER:
        raise ValueError(f"ONEDNN_MAX_CPU_ISA={cap!r}: not one of {', '.join(ISA_ORDER)}")
    best = best_isa(flags)
    if not best:
        return ""
    return min(best, cap, key=ISA_ORDER.index)


#: [-] a CPU without native bf16 (AVX512-BF16 or AMX) runs the bf16 backend in oneDNN's reference
#: code, measured 1.54 s a frame on an AVX2-only EPYC against 0.062 s for channels_last (2026-11-25)
NATIVE_BF16 = ("avx512_bf16", "amx_bf16")
#: [s] one U-Net frame, AVX2-only EPYC, one thread (docs/benchmarks.md, 2026-11-25): what asking
#: for bf16 there would cost, quoted when it is refused
EMULATED_BF16_FRAME_S, FP32_FRAME_S = 1.541, 0.062


def resolve_backend(name: Optional[str]) -> str:
    """The backend a ~backend / unet_backend value means: empty or None is DEFAULT_BACKEND; an
    unknown name is a ValueError naming the known ones."""
    backend = name or DEFAULT_BACKEND
    if backend not in BACKENDS:
        raise ValueError(f"unknown U-Net backend {backend!r}: one of {', '.join(BACKENDS)} (empty: {DEFAULT_BACKEND})")
    return backend


def native_bf16(flags: Optional[Iterable[str]] = None) -> bool:
    """Whether this CPU runs bf16 convolutions natively (else oneDNN emulates them, 25x slower)."""
    flags = set(cpu_flags() if flags is None else flags)
    return any(f in flags for f in NATIVE_BF16)


def refuse_emulated(backend: str, flags: Optional[Iterable[str]] = None) -> Optional[str]:
    """Why `backend` may not run on this CPU, or None: a bf16 backend needs native bf16 (the
    fast mode of issue #53); oneDNN would otherwise emulate it 25x slower than the default."""
    if backend not in BF16_BACKENDS or native_bf16(flags):
        return None
    return (
        f"U-Net backend {backend}: this CPU has no native bf16 (none of the flags {', '.join(NATIVE_BF16)}), so "
        f"oneDNN would emulate it: {EMULATED_BF16_FRAME_S:.2f} s a frame against {FP32_FRAME_S:.3f} s for fp32 "
        f"channels_last (measured on an AVX2-only EPYC), about {EMULATED_BF16_FRAME_S / FP32_FRAME_S:.0f}x "
        f"slower; run the default, fp32 {DEFAULT_BACKEND} (leave unet_backend empty)"
    )


def test_backend(flags: Optional[Iterable[str]] = None) -> str:
    """The U-Net backend the end-to-end tests run on this CPU (scripts/test.sh exports it as
    ASG_TEST_UNET_BACKEND): the shipped default, DEFAULT_BACKEND, unless it is a bf16 one and this
    CPU would emulate it; then channels_last, the portable fp32 backend."""
    if DEFAULT_BACKEND not in BF16_BACKENDS or native_bf16(flags):
        return DEFAULT_BACKEND
    return "channels_last"


def pin() -> str:
    """Caps oneDNN at ISA_CAP unless the environment already names a cap; call before the first
    inference (asg_perception.inference does, at import). Returns the cap in force."""
    cap = os.environ.get(ENV[0]) or os.environ.get(ENV[1]) or ISA_CAP
    for name in ENV:
        os.environ[name] = cap
    return cap


def identity(backend: str, threads: int, flags: Optional[Iterable[str]] = None) -> str:
    """The segmenter's numerics as one string, stored with every campaign and compared by replay:
    'BACKEND isa=EFFECTIVE threads=N torch=VERSION'."""
    import torch

    isa = effective_isa(cpu_flags() if flags is None else flags)
    if isa and backend not in BF16_BACKENDS:  # fp32 convolutions: AVX512_CORE and above run the same kernels
        isa = min(isa, FP32_TOP, key=ISA_ORDER.index)
    return f"{backend} isa={isa or 'unknown'} threads={int(threads)} torch={torch.__version__}"


#: the effective ISAs on which the fp32 default's closed-loop runs were replayed bit for bit
#: against the one stored reference set (tests/reference, docs/benchmarks.md "CPU classes"):
#: between these, an fp32 run replays whatever ISA recorded it
FP32_PORTABLE_ISAS = ("AVX2", "AVX512_CORE")


def can_reproduce(recorded: str, here: str) -> Optional[str]:
    """None when a run whose segmenter numerics were `recorded` replays bit for bit where they are
    `here`; otherwise the reason, in words. An empty `recorded` (runs from before issue #36) is
    taken as reproducible. fp32 backends ignore the ISA between FP32_PORTABLE_ISAS, and the
    backend between FP32_PORTABLE_BACKENDS (measured portable); bf16 ones need the recorded ISA."""
    if not recorded or recorded == here:
        return None
    want = dict(kv.split("=", 1) for kv in recorded.split()[1:] if "=" in kv)
    got = dict(kv.split("=", 1) for kv in here.split()[1:] if "=" in kv)
    why = []
    same_function = {recorded.split()[0], here.split()[0]} <= set(FP32_PORTABLE_BACKENDS)
    if recorded.split()[0] != here.split()[0] and not same_function:
        why.append(f"backend {recorded.split()[0]} was recorded, this segmenter runs {here.split()[0]}")
    keys = (("isa", "oneDNN kernels"), ("threads", "torch threads"), ("torch", "torch"))
    if (
        recorded.split()[0] not in BF16_BACKENDS
        and want.get("isa") in FP32_PORTABLE_ISAS
        and got.get("isa") in FP32_PORTABLE_ISAS
    ):
        keys = keys[1:]
    for key, what in keys:
        if want.get(key) != got.get(key):
            why.append(f"{what}: recorded {want.get(key)}, here {got.get(key)}")
    if not why and (len(keys) == 2 or same_function):  # fp32 across portable ISAs or backends, all else equal
        return None
    return "; ".join(why) or f"recorded {recorded!r}, here {here!r}"


if __name__ == "__main__":  # python3 -m asg_perception.numerics test-backend
    import sys

    if sys.argv[1:] != ["test-backend"]:
        sys.exit("usage: python3 -m asg_perception.numerics test-backend")
    print(test_backend())
