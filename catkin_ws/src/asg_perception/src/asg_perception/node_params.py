"""The segmenter node's parameters (asg_lockstep.params; docs/perception.md quotes this table)."""

from asg_lockstep.params import Param

from .numerics import BACKENDS

SEGMENTER = [
    Param(
        "model",
        str,
        "flawed",
        "-",
        "a shipped model name (`full`, `flawed`, `full_lite`, `flawed_lite`) or a model file path",
        rule=lambda v: v != "",
        rule_text="not empty",
    ),
    Param(
        "backend",
        str,
        "",
        "-",
        "inference backend (above); empty: the shipped default, `asg_perception.numerics.DEFAULT_BACKEND`",
        choices=("",) + tuple(BACKENDS),
    ),
    Param("threads", int, 1, "-", "torch CPU threads", lo=1, hi=64),
    Param(
        "width",
        int,
        256,
        "px",
        "frame width the segmenter is made for",
        lo=32,
        hi=4096,
        rule=lambda v: v % 32 == 0,
        rule_text="a multiple of 32",
    ),
    Param(
        "height",
        int,
        256,
        "px",
        "frame height the segmenter is made for",
        lo=32,
        hi=4096,
        rule=lambda v: v % 32 == 0,
        rule_text="a multiple of 32",
    ),
    Param("ack_name", str, "segmenter", "-", "name used in `stack_ack`", rule=lambda v: v != "", rule_text="not empty"),
]
