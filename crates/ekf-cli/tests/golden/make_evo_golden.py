#!/usr/bin/env python3
"""Regenerates the evo golden files: evo_ref.txt, evo_est.txt and evo_expected.json.

Needs numpy and evo (`python3 -m venv .venv && .venv/bin/pip install evo`); run from this
folder with the venv's python. The Rust test `eval_golden.rs` only reads the outputs, so
CI needs neither. evo's numbers come from its command-line tools (`--save_results`), run
as a user would run them.
"""

import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
BIN = Path(sys.executable).parent
T0_NS = 1_700_000_000_000_000_000


def write_tum(path, stamps_ns, x, y, yaw):
    with open(path, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for t, xi, yi, th in zip(stamps_ns, x, y, yaw):
            t = int(t)
            f.write(f"{t // 10**9}.{t % 10**9:09d} {float(xi)!r} {float(yi)!r} 0 0 0 "
                    f"{float(np.sin(th / 2))!r} {float(np.cos(th / 2))!r}\n")


def make_inputs():
    rng = np.random.default_rng(20261122)
    # Reference: 10 Hz for 12 s, a unicycle with varying speed and turn rate.
    n = 121
    stamps = T0_NS + np.arange(n, dtype=np.int64) * 100_000_000
    v = 0.5 + 0.2 * np.sin(np.arange(n) / 7.0)
    w = 0.3 * np.sin(np.arange(n) / 11.0) + 0.05 * rng.standard_normal(n)
    yaw = np.cumsum(w * 0.1) + 0.4
    x = 1.0 + np.cumsum(v * 0.1 * np.cos(yaw))
    y = -2.0 + np.cumsum(v * 0.1 * np.sin(yaw))
    yaw = np.angle(np.exp(1j * yaw))
    write_tum(HERE / "evo_ref.txt", stamps, x, y, yaw)
    # Estimate: every pose but a few, stamps jittered by up to 3 ms, a rigid offset,
    # drift and noise; plus poses before and after the reference (unmatched).
    keep = np.ones(n, dtype=bool)
    keep[[5, 6, 40, 77]] = False
    idx = np.nonzero(keep)[0]
    jitter = rng.integers(-3_000_000, 3_000_001, idx.size)
    est_stamps = stamps[idx] + jitter
    ang = 0.05
    c, s = np.cos(ang), np.sin(ang)
    drift = np.arange(idx.size) * 0.002
    ex = c * x[idx] - s * y[idx] + 0.3 + drift + 0.02 * rng.standard_normal(idx.size)
    ey = s * x[idx] + c * y[idx] - 0.1 + 0.02 * rng.standard_normal(idx.size)
    eyaw = np.angle(np.exp(1j * (yaw[idx] + ang + 0.02 * rng.standard_normal(idx.size))))
    pre = np.array([T0_NS - 500_000_000])
    post = np.array([stamps[-1] + 400_000_000])
    est_stamps = np.concatenate([pre, est_stamps, post])
    ex = np.concatenate([[0.0], ex, [ex[-1]]])
    ey = np.concatenate([[0.0], ey, [ey[-1]]])
    eyaw = np.concatenate([[0.0], eyaw, [eyaw[-1]]])
    write_tum(HERE / "evo_est.txt", est_stamps, ex, ey, eyaw)


def run(tool, files, *args):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "result.zip"
        subprocess.run(
            [str(BIN / tool), "tum", *(str(HERE / f) for f in files),
             *args, "--save_results", str(out), "--no_warnings"],
            check=True, stdout=subprocess.DEVNULL)
        with zipfile.ZipFile(out) as z:
            stats = json.loads(z.read("stats.json"))
            errors = np.load(z.open("error_array.npy"))
    stats = {k: stats[k] for k in ("rmse", "mean", "median", "std", "min", "max", "sse")}
    return stats, int(errors.size)


def main():
    make_inputs()
    # The estimate has fewer poses than the reference; "swapped" runs exchange the files,
    # so that the other trajectory drives the time association.
    cases = {
        "ape_none": ("evo_ape", []),
        "ape_none_swapped": ("evo_ape", [], True),
        "ape_align": ("evo_ape", ["-a"]),
        "ape_align_scale": ("evo_ape", ["-a", "-s"]),
        "ape_align_first_20": ("evo_ape", ["-a", "--n_to_align", "20"]),
        "rpe_delta_1": ("evo_rpe", []),
        "rpe_delta_3": ("evo_rpe", ["--delta", "3", "--delta_unit", "f"]),
        "rpe_delta_3_all_pairs": ("evo_rpe", ["--delta", "3", "--delta_unit", "f", "--all_pairs"]),
        "rpe_delta_1_swapped": ("evo_rpe", [], True),
    }
    expected = {}
    for name, (tool, args, *swapped) in cases.items():
        files = ["evo_ref.txt", "evo_est.txt"]
        if swapped:
            files.reverse()
        trans, count = run(tool, files, *args, "-r", "trans_part")
        angle, _ = run(tool, files, *args, "-r", "angle_deg")
        expected[name] = {"count": count, "translation_m": trans, "heading_error_deg": angle}
    version = subprocess.run([str(BIN / "evo"), "pkg", "--version"], capture_output=True,
                             text=True).stdout.strip()
    doc = {"generator": f"make_evo_golden.py with evo {version}", "cases": expected}
    (HERE / "evo_expected.json").write_text(json.dumps(doc, indent=2) + "\n")


if __name__ == "__main__":
    main()
