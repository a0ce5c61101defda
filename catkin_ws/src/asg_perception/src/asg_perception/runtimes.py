"""Issue #24's backend table: the U-Net on torch and on the two inference runtimes from PyPI,
each in the precisions this CPU offers, side by side in one run (no rospy).

    python3 -m asg_perception.runtimes MODEL.pt --data DIR [--frames 50] [--calibration 32] [--repeats 5] [--json OUT]

Every row runs the whole path the segmenter runs: uint8 RGB in, labels out (scaling, layout and
argmax included), one frame at a time on one thread. Rows:
- torch: ``eager`` fp32 (the reference every other row is compared with), ``channels_last`` fp32,
  ``bf16`` (the shipped backend, asg_perception.inference);
- ONNX Runtime (``onnxruntime``): the model exported to ONNX, fp32; and int8, quantized statically
  (QDQ, per-channel weights, activations calibrated on `--calibration` other frames);
- OpenVINO (``openvino``): the same ONNX file, fp32 and bf16 (its inference precision hint).

Printed and written per row: ms per frame (median of `--repeats` passes, the rows taking turns
pass by pass so that a load on the machine falls on all alike), GFLOP/s (the convolutions' FLOP,
asg_perception.peak), its share of the fp32 convolution peak of torch on this core, and the labels'
agreement with eager fp32 (pixels, and frames equal). The runtimes are measured, not shipped: the
segmenter node runs torch only. A runtime that is not installed is reported as such, with the
command that installs it (scripts/common.sh, PIP_PACKAGES).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Callable, Dict

import numpy as np
import torch

from .data import DatasetError, load_frames
from .inference import Segmenter
from .peak import conv_peak_gflops, unet_flops
from .train import load_model


def _prep(rgb: np.ndarray) -> np.ndarray:
    """uint8 H x W x 3 -> float32 1 x 3 x H x W in [0, 1], as the torch backends scale it."""
    return np.ascontiguousarray(rgb.transpose(2, 0, 1)[None], dtype=np.float32) / np.float32(255.0)


def export_onnx(model_path: str, path: str, height: int = 256, width: int = 256) -> str:
    model = load_model(model_path)
    with torch.no_grad():
        torch.onnx.export(
            model,
            torch.zeros(1, 3, height, width),
            path,
            input_names=["rgb"],
            output_names=["logits"],
            opset_version=13,
        )
    return path


def onnxruntime_runner(onnx_path: str, threads: int = 1) -> Callable[[np.ndarray], np.ndarray]:
    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    sess = ort.InferenceSession(onnx_path, opts, providers=["CPUExecutionProvider"])
    return lambda rgb: sess.run(None, {"rgb": _prep(rgb)})[0][0].argmax(0).astype(np.uint8)


#: Static int8 quantization, run in a process of its own: Debian's torch registers an older
#: onnx.proto in protobuf's descriptor pool, and the `onnx` package then fails to import beside it.
_QUANTIZE = """
import sys
import numpy as np
from onnxruntime.quantization import CalibrationDataReader, QuantFormat, QuantType, quantize_static

class Frames(CalibrationDataReader):
    def __init__(self, frames):
        self.it = iter(frames)

    def get_next(self):
        f = next(self.it, None)
        return None if f is None else {"rgb": f}

src, out, calib = sys.argv[1:4]
quantize_static(src, out, Frames(np.load(calib)), quant_format=QuantFormat.QDQ, per_channel=True,
                activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8)
"""


def quantize_int8(onnx_path: str, out_path: str, calibration: np.ndarray) -> str:
    """The ONNX model quantized to int8 (QDQ; per-channel int8 weights, uint8 activations whose
    ranges come from the `calibration` frames). Raises RuntimeError with the quantizer's words."""
    calib = out_path + ".calibration.npy"
    np.save(calib, np.stack([_prep(f) for f in calibration]))
    proc = subprocess.run([sys.executable, "-c", _QUANTIZE, onnx_path, out_path, calib], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"int8 quantization failed: {proc.stderr.strip().splitlines()[-1:]}")
    return out_path


def openvino_runner(onnx_path: str, precision: str, threads: int = 1) -> Callable[[np.ndarray], np.ndarray]:
    import openvino as ov

    core = ov.Core()
    config = {
        "INFERENCE_NUM_THREADS": threads,
        "NUM_STREAMS": 1,
        "PERFORMANCE_HINT": "LATENCY",
        "INFERENCE_PRECISION_HINT": precision,
    }
    compiled = core.compile_model(core.read_model(onnx_path), "CPU", config)
    request = compiled.create_infer_request()
    return lambda rgb: request.infer({0: _prep(rgb)})[compiled.output(0)][0].argmax(0).astype(np.uint8)


def runners(model_path: str, workdir: str, calibration: np.ndarray, threads: int = 1) -> Dict[str, object]:
    """Row name -> callable (uint8 RGB -> labels), or a string saying why the row could not run."""
    out: Dict[str, object] = {}
    for backend, name in (
        ("eager", "torch eager fp32"),
        ("channels_last", "torch channels_last fp32"),
        ("bf16", "torch bf16 (shipped)"),
    ):
        out[name] = Segmenter(model_path, backend, threads)
    onnx_path = export_onnx(model_path, os.path.join(workdir, "unet.onnx"))
    try:
        out["ONNX Runtime fp32"] = onnxruntime_runner(onnx_path, threads)
    except ImportError as e:
        out["ONNX Runtime"] = f"not installed ({e}); scripts/common.sh installs it"
    else:
        try:
            int8 = quantize_int8(onnx_path, os.path.join(workdir, "unet_int8.onnx"), calibration)
            out["ONNX Runtime int8 (static, QDQ)"] = onnxruntime_runner(int8, threads)
        except RuntimeError as e:
            out["ONNX Runtime int8 (static, QDQ)"] = str(e)
    try:
        out["OpenVINO fp32"] = openvino_runner(onnx_path, "f32", threads)
        out["OpenVINO bf16"] = openvino_runner(onnx_path, "bf16", threads)
    except ImportError as e:
        out["OpenVINO"] = f"not installed ({e}); scripts/common.sh installs it"
    return out


def measure(model_path: str, rgb: np.ndarray, calibration: np.ndarray, repeats: int = 5, threads: int = 1) -> dict:
    """The table's figures for frames `rgb`; int8 activations calibrated on other frames, `calibration`."""
    torch.set_num_threads(threads)
    flops = unet_flops(load_model(model_path))
    peak = conv_peak_gflops()
    with tempfile.TemporaryDirectory() as workdir:
        rows = runners(model_path, workdir, calibration, threads)
        live = {k: f for k, f in rows.items() if callable(f)}
        labels = {k: np.stack([f(x) for x in rgb]) for k, f in live.items()}  # also warms every runner up
        times = {k: [] for k in live}
        for _ in range(repeats):
            for k, f in live.items():
                t0 = time.perf_counter()
                for x in rgb:
                    f(x)
                times[k].append((time.perf_counter() - t0) / len(rgb) * 1000)
    ref = labels["torch eager fp32"]
    table = []
    for k, v in rows.items():
        if not callable(v):
            table.append({"backend": k, "error": v})
            continue
        ms = statistics.median(times[k])
        table.append(
            {
                "backend": k,
                "ms_per_frame": ms,
                "runs_ms": times[k],
                "gflops": flops / ms / 1e6,
                "share_of_fp32_conv_peak": flops / ms / 1e6 / peak,
                "pixels_agreeing_with_eager": float((labels[k] == ref).mean()),
                "frames_equal_to_eager": int((labels[k] == ref).all(axis=(1, 2)).sum()),
                "obstacle_share": float((labels[k] == 1).mean()),
            }
        )
    return {
        "model": os.path.basename(model_path),  # the file name: paths differ by machine
        "frames": int(len(rgb)),
        "threads": threads,
        "gflop_per_frame": flops / 1e9,
        "fp32_conv_peak_gflops": peak,
        "torch": torch.__version__,
        "rows": table,
    }


def format_table(r: dict) -> str:
    base = next(x["ms_per_frame"] for x in r["rows"] if x["backend"] == "torch eager fp32")
    lines = [
        f"{r['frames']} frames, {r['threads']} thread(s), {r['gflop_per_frame']:.2f} GFLOP a frame, "
        f"fp32 convolution peak {r['fp32_conv_peak_gflops']:.0f} GFLOP/s",
        "",
        "| backend | ms per frame | x eager | GFLOP/s | share of fp32 peak | pixels agreeing with eager fp32 "
        "| frames equal | obstacle pixels |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for x in r["rows"]:
        if "error" in x:
            lines.append(f"| {x['backend']} | {x['error']} | | | | | | |")
            continue
        lines.append(
            f"| {x['backend']} | {x['ms_per_frame']:.2f} | {base / x['ms_per_frame']:.2f}x | {x['gflops']:.0f} | "
            f"{100 * x['share_of_fp32_conv_peak']:.0f} % | {100 * x['pixels_agreeing_with_eager']:.3f} % | "
            f"{x['frames_equal_to_eager']}/{r['frames']} | {100 * x['obstacle_share']:.2f} % |"
        )
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(prog="runtimes", description=__doc__.split("\n\n")[0])
    p.add_argument("model")
    p.add_argument("--data", required=True, help="dataset folder (asg_sim_dataset output): the frames timed")
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument(
        "--calibration", type=int, default=32, help="frames after the timed ones that calibrate int8 activations"
    )
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--json", help="write the figures here")
    a = p.parse_args(argv)
    if a.frames < 1 or a.repeats < 1 or a.calibration < 1:
        p.error("--frames, --repeats and --calibration must be at least 1")
    try:
        frames = load_frames(a.data, a.frames + a.calibration, progress=False)
    except (DatasetError, ValueError) as e:
        print(f"runtimes: {e}", file=sys.stderr)
        return 2
    if len(frames) < a.frames + a.calibration:
        print(f"runtimes: {a.data} has {len(frames)} frames, {a.frames} + {a.calibration} needed", file=sys.stderr)
        return 2
    r = measure(a.model, frames.rgb[: a.frames], frames.rgb[a.frames :], a.repeats, a.threads)
    print(format_table(r))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(r, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
