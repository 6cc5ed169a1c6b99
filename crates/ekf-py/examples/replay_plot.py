"""Replay the bundled ACES log (UT Austin) through the filter with laser lines and the
compass against the building's line map, and plot the estimate against the log's reference
trajectory, with the map's walls and the position error over time.

    pip install ./crates/ekf-py matplotlib
    python crates/ekf-py/examples/replay_plot.py --out aces.png
"""

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import ekf_loc

TESTDATA = Path(__file__).resolve().parents[3] / "testdata"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--log", type=Path, default=TESTDATA / "aces.mcap")
    parser.add_argument("--map", type=Path, default=TESTDATA / "aces-map.json")
    parser.add_argument("--mode", default="laser+compass",
                        choices=["odometry", "compass", "laser", "laser+compass"])
    parser.add_argument("--out", type=Path, default=Path("aces-replay.png"))
    args = parser.parse_args()

    result = ekf_loc.replay(args.log, mode=args.mode, map=args.map, init_from_truth=True)
    walls = ekf_loc.LineMap.load(args.map).segments
    accuracy = result.summary["accuracy"]
    print(f"{result.summary['poses_written']} poses, {args.mode}: "
          f"position RMSE {accuracy['position_rmse_m']:.3f} m, "
          f"heading RMSE {accuracy['heading_rmse_deg']:.2f}°")

    # The estimate at the reference's stamps (both are in log time, seconds).
    x = np.interp(result.reference_t, result.t, result.x)
    y = np.interp(result.reference_t, result.t, result.y)
    error = np.hypot(x - result.reference_x, y - result.reference_y)

    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(13, 6),
                                     gridspec_kw={"width_ratios": [3, 2]})
    for (x0, y0), (x1, y1) in walls:
        ax.plot([x0, x1], [y0, y1], color="0.7", linewidth=0.8)
    ax.plot(result.reference_x, result.reference_y, label="reference", color="black")
    ax.plot(result.x, result.y, label=f"EKF ({args.mode})", color="tab:red", linewidth=1)
    # Frame the drive (the map also has stray walls seen through windows far outside).
    margin = 3.0
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal", title=args.log.name,
           xlim=(result.reference_x.min() - margin, result.reference_x.max() + margin),
           ylim=(result.reference_y.min() - margin, result.reference_y.max() + margin))
    ax.legend()
    ax_err.plot(result.reference_t - result.reference_t[0], error, color="tab:red")
    ax_err.set(xlabel="time (s)", ylabel="position error (m)",
               title=f"RMSE {accuracy['position_rmse_m']:.3f} m")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
