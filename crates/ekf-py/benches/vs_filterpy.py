"""One EKF step (predict from wheel speeds + compass + 4 laser lines) timed in one run:
FilterPy running the paper's model (tests/python/paper_filterpy.py) two ways, ekf_loc one
call at a time, and ekf_loc's batch API; with --rust also ekf-core's criterion benchmark
of the same step (cargo bench -p ekf-core --bench filter), for the batch-vs-Rust ratio.

The two FilterPy baselines:

- "sequential": what ekf_loc does, written on FilterPy: five updates a step (the compass,
  then each line), each gated on its own NIS (FilterPy's update, then y^T S^-1 y, and
  the update undone if refused);
- "stacked": the cheapest way we found to write the step on FilterPy: one update of the
  9-row stacked measurement (compass + 4 lines; eq. 16), h(x) and H vectorised over the
  walls, no gate. Not the same filter (no per-measurement gates, one linearisation point
  for all five), but FilterPy's cost with one update a step instead of five.

All variants run the same 2,000-step drive with four matched walls every step. ekf_loc's
gates are on. Needs a release build of ekf_loc (pip install ./crates/ekf-py, or maturin
develop --release) and filterpy:

    python crates/ekf-py/benches/vs_filterpy.py [--rust]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tests" / "python"))

import ekf_loc  # noqa: E402
from paper_filterpy import MOUNT, PaperEKF, config, make_scenario, wrap  # noqa: E402

X0 = (4.0, 2.5, 0.3)
P0 = np.eye(3) * 1e-3


def per_step(run, steps, repeats):
    """Median over `repeats` runs of the wall time per step (µs)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append((time.perf_counter() - start) / steps * 1e6)
    return statistics.median(times)


def stacked_update(f, heading, variance, z, r, walls):
    """One FilterPy update of the compass and the lines stacked: z = [heading, r0, psi0,
    r1, psi1, ...], R block diagonal, and h(x), H and the residual (angles wrapped)
    computed for all walls at once with numpy, as paper_filterpy's line_h and
    line_jacobian compute them one wall at a time."""
    n = len(walls)
    zs = np.empty(1 + 2 * n)
    zs[0] = heading
    zs[1:] = np.asarray(z).ravel()
    rs = np.zeros((1 + 2 * n, 1 + 2 * n))
    rs[0, 0] = variance
    for j in range(n):
        rs[1 + 2 * j:3 + 2 * j, 1 + 2 * j:3 + 2 * j] = r[j]
    rho, beta = walls[:, 0], walls[:, 1]
    cb, sb = np.cos(beta), np.sin(beta)
    mx, my, mth = MOUNT

    def geometry(x):
        c, s = math.cos(x[2]), math.sin(x[2])
        xs, ys = x[0] + c * mx - s * my, x[1] + s * mx + c * my
        dxs, dys = -s * mx - c * my, c * mx - s * my
        return xs, ys, x[2] + mth, rho - xs * cb - ys * sb, dxs, dys

    def jacobian(x):
        _, _, _, cc, dxs, dys = geometry(x)
        sign = np.where(cc < 0, -1.0, 1.0)
        h = np.zeros((1 + 2 * n, 3))
        h[0, 2] = 1.0
        h[1::2, 0] = -sign * cb
        h[1::2, 1] = -sign * sb
        h[1::2, 2] = -sign * (dxs * cb + dys * sb)
        h[2::2, 2] = -1.0
        return h

    def hx(x):
        _, _, ths, cc, _, _ = geometry(x)
        out = np.empty(1 + 2 * n)
        out[0] = x[2]
        out[1::2] = np.abs(cc)
        out[2::2] = beta - ths + np.where(cc < 0, math.pi, 0.0)
        return out

    def residual(a, b):
        d = a - b
        d[0::2] = np.remainder(d[0::2] + math.pi, 2 * math.pi) - math.pi  # heading, psi
        return d

    f.update(zs, jacobian, hx, R=rs, residual=residual)
    f.x[2] = wrap(f.x[2])


def rust_step_us():
    """Median of ekf-core's criterion benchmark of predict + compass + 4 lines (f64)."""
    bench = subprocess.run(
        ["cargo", "bench", "-p", "ekf-core", "--bench", "filter", "--",
         "predict_compass_4_lines/f64", "--warm-up-time", "2", "--measurement-time", "5"],
        cwd=ROOT, capture_output=True, text=True,
    )
    if bench.returncode != 0:
        sys.exit(f"cargo bench failed:\n{bench.stderr}")
    target = json.loads(subprocess.run(
        ["cargo", "metadata", "--no-deps", "--format-version", "1"],
        cwd=ROOT, check=True, capture_output=True, text=True).stdout)["target_directory"]
    path = Path(target) / "criterion/ekf/predict_compass_4_lines/f64/new/estimates.json"
    return json.loads(path.read_text())["median"]["point_estimate"] / 1000


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--rust", action="store_true", help="also run the criterion bench")
    args = parser.parse_args()
    if ekf_loc._ekf_loc._debug_build:
        sys.exit("ekf_loc is a debug build; install a release build to benchmark it")

    n = args.steps
    wheels, compass, observed, covs, walls, _ = make_scenario(n, lines_every=1)
    variance = config()["compass"]["variance"]
    # Python floats and per-step arrays, made once: the loops time the APIs, not indexing.
    wheel_rows = [tuple(map(float, w)) for w in wheels]
    headings = [float(h) for h in compass]
    lines = [(observed[k], covs[k], walls[k]) for k in range(n)]

    def filterpy():
        f = PaperEKF(X0, P0)
        for k in range(n):
            f.predict_wheels(*wheel_rows[k])
            f.update_compass(headings[k], variance)
            z, r, m = lines[k]
            for j in range(4):
                f.update_line(z[j], r[j], m[j])

    def filterpy_stacked():
        f = PaperEKF(X0, P0, gating=False)
        for k in range(n):
            f.predict_wheels(*wheel_rows[k])
            z, r, m = lines[k]
            stacked_update(f, headings[k], variance, z, r, m)

    def calls():
        f = ekf_loc.Filter(X0, P0, config())
        for k in range(n):
            f.predict_wheels(*wheel_rows[k])
            f.update_compass(headings[k])
            f.update_lines(*lines[k])

    def batch():
        f = ekf_loc.Filter(X0, P0, config())
        f.run(wheels=wheels, compass=compass, line_observed=observed,
              line_covariances=covs, line_map=walls)

    # FilterPy is slow: fewer repeats give the same median to a few percent.
    t_filterpy = per_step(filterpy, n, max(1, args.repeats // 3))
    t_stacked = per_step(filterpy_stacked, n, max(1, args.repeats // 3))
    t_calls = per_step(calls, n, args.repeats)
    t_batch = per_step(batch, n, args.repeats * 10)
    load = os.getloadavg()[0]
    print(f"predict + compass + 4 lines, {n} steps, median per step "
          f"(1-minute load average {load:.2f} on {os.cpu_count()} cores):")
    print(f"  FilterPy, sequential (5 gated updates)   {t_filterpy:9.2f} µs")
    print(f"  FilterPy, stacked (one 9-row update)     {t_stacked:9.2f} µs")
    print(f"  ekf_loc, one call at a time              {t_calls:9.2f} µs   "
          f"{t_filterpy / t_calls:5.1f}x sequential, {t_stacked / t_calls:5.1f}x stacked")
    print(f"  ekf_loc, batch API (run)                 {t_batch:9.3f} µs   "
          f"{t_filterpy / t_batch:5.0f}x sequential, {t_stacked / t_batch:5.0f}x stacked")
    if args.rust:
        t_rust = rust_step_us()
        print(f"  ekf-core criterion (Rust)                {t_rust:9.3f} µs   "
              f"batch / Rust = {t_batch / t_rust:.2f} (target <= 2)")


if __name__ == "__main__":
    main()
