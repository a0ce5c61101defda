"""Issue #36: the oneDNN ISA cap and the numerics identity that replay compares (no rospy)."""

import os

import pytest

from asg_perception import numerics as n

AVX512 = {"sse4_1", "avx", "avx2", "avx512f", "avx512bw", "avx512vl", "avx512dq"}
EPYC = AVX512 | {"avx512_vnni", "avx512_bf16"}  # AVX512-BF16, no AMX (the CI machine)
XEON_AMX = EPYC | {"amx_bf16", "amx_tile", "amx_int8"}


def test_best_and_effective_isa_by_cpu():
    assert n.best_isa({"sse4_1", "avx", "avx2"}) == "AVX2"
    assert n.best_isa(AVX512) == "AVX512_CORE"
    assert n.best_isa(EPYC) == "AVX512_CORE_BF16"
    assert n.best_isa(XEON_AMX) == "AVX512_CORE_AMX"
    assert n.best_isa(set()) == ""
    # the cap makes an AMX Xeon and an AVX512-BF16 EPYC run the same kernels
    assert n.effective_isa(XEON_AMX, n.ISA_CAP) == n.effective_isa(EPYC, n.ISA_CAP) == "AVX512_CORE_BF16"
    assert n.effective_isa(XEON_AMX, "ALL") == "AVX512_CORE_AMX"
    assert n.effective_isa(AVX512, n.ISA_CAP) == "AVX512_CORE"  # below the cap: the CPU's best
    with pytest.raises(ValueError, match="ONEDNN_MAX_CPU_ISA"):
        n.effective_isa(EPYC, "AVX9000")


def test_the_package_pins_the_cap_before_torch_runs_a_kernel():
    import subprocess
    import sys

    code = "import os, asg_perception; print(os.environ['ONEDNN_MAX_CPU_ISA'], os.environ['DNNL_MAX_CPU_ISA'])"
    env = {k: v for k, v in os.environ.items() if k not in n.ENV}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == [n.ISA_CAP, n.ISA_CAP]  # pinned at import
    env["ONEDNN_MAX_CPU_ISA"] = "ALL"  # a user's own cap is left as it is
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["ALL", "ALL"]


def test_identity_and_what_can_replay_what():
    here = n.identity("bf16", 1, flags=EPYC)
    assert here.startswith("bf16 isa=AVX512_CORE_BF16 threads=1 torch=")
    # fp32 backends: VNNI, BF16 and AMX do not change fp32 convolutions
    assert n.identity("channels_last", 1, flags=XEON_AMX).startswith("channels_last isa=AVX512_CORE ")
    assert n.can_reproduce(here, here) is None
    assert n.can_reproduce("", here) is None  # runs recorded before issue #36
    amx = here.replace("AVX512_CORE_BF16", "AVX512_CORE_AMX")
    why = n.can_reproduce(amx, here)
    assert "oneDNN kernels: recorded AVX512_CORE_AMX, here AVX512_CORE_BF16" in why
    why = n.can_reproduce(here.replace("threads=1", "threads=2"), here)
    assert "torch threads: recorded 2, here 1" in why
    assert "backend eager was recorded" in n.can_reproduce(here.replace("bf16", "eager", 1), here)
    # issue #53: channels_last and polyphase replay each other's runs (one fp32 function, measured),
    # across the portable ISAs too; not across threads, and not with eager or bf16
    cl, pp = "channels_last isa=AVX2 threads=1 torch=1.13.0a0", "polyphase isa=AVX512_CORE threads=1 torch=1.13.0a0"
    assert n.can_reproduce(cl, pp) is None and n.can_reproduce(pp, cl) is None
    assert "torch threads: recorded 2, here 1" in n.can_reproduce(cl.replace("threads=1", "threads=2"), pp)
    assert "backend eager was recorded" in n.can_reproduce(cl.replace("channels_last", "eager"), pp)
    assert "backend bf16 was recorded" in n.can_reproduce(pp.replace("polyphase", "bf16"), pp)
    assert "oneDNN kernels: recorded SSE41" in n.can_reproduce(cl.replace("AVX2", "SSE41"), pp)


def test_the_default_is_fp32_and_bf16_is_refused_where_it_would_be_emulated():
    # issue #53: one stack identity on every CPU: the default is fp32 (polyphase, the same function
    # as channels_last), so the end-to-end tests run it on every CPU class
    assert n.DEFAULT_BACKEND == "polyphase" and n.DEFAULT_BACKEND not in n.BF16_BACKENDS
    assert n.DEFAULT_BACKEND in n.FP32_PORTABLE_BACKENDS
    avx2 = frozenset({"sse4_1", "avx", "avx2", "fma"})
    for flags in (EPYC, XEON_AMX, avx2):
        assert n.test_backend(flags) == n.DEFAULT_BACKEND
        assert n.refuse_emulated(n.DEFAULT_BACKEND, flags) is None
    # bf16, the fast mode, runs where the CPU has it natively ...
    assert n.native_bf16(EPYC) and n.refuse_emulated("bf16", EPYC) is None
    assert n.native_bf16(XEON_AMX) and n.refuse_emulated("bf16", XEON_AMX) is None
    # ... and is refused elsewhere with the measured cost (2026-11-25, AVX2-only EPYC: 1.54 s a
    # frame in oneDNN's reference code against 0.062 s for channels_last)
    why = n.refuse_emulated("bf16", avx2)
    assert not n.native_bf16(avx2)
    assert "no native bf16" in why and "1.54 s a frame" in why and "25x slower" in why


def test_an_empty_backend_is_the_one_default_and_a_wrong_one_is_named():
    # issue #38: the default has one home; launch files pass "" for it
    assert n.DEFAULT_BACKEND in n.BACKENDS
    assert n.resolve_backend("") == n.resolve_backend(None) == n.DEFAULT_BACKEND
    assert [n.resolve_backend(b) for b in n.BACKENDS] == list(n.BACKENDS)
    with pytest.raises(ValueError, match=r"unknown U-Net backend 'fp16': one of eager, channels_last"):
        n.resolve_backend("fp16")
    from asg_perception import inference

    assert inference.BACKENDS is n.BACKENDS and inference.DEFAULT_BACKEND is n.DEFAULT_BACKEND
