"""The Python module ekf_loc: lines, maps, matching and the Localizer on a simulated room;
`replay` against `ekf replay --tum` on a bundled log; clear exceptions for bad input.

Run: scripts/test-all.sh (it builds and installs ekf_loc into .venv with maturin).
"""

import json
import math
import os
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

import ekf_loc
from conftest import ROOT, run_ekf

ACES = ROOT / "testdata" / "aces.mcap"
ACES_MAP = ROOT / "testdata" / "aces-map.json"

# A 10 m x 6 m room around the origin: walls x = 7, x = -3, y = 4, y = -2 as (rho, beta).
ROOM = [(7.0, 0.0), (3.0, math.pi), (4.0, math.pi / 2), (2.0, -math.pi / 2)]
ROOM_SEGMENTS = [
    [[7, -2], [7, 4]], [[-3, 4], [-3, -2]], [[7, 4], [-3, 4]], [[-3, -2], [7, -2]]
]
# A 270° scanner, 0.5° steps (a full turn would cut the wall behind it at the seam).
BEAMS = 541
ANGLE_MIN = -0.75 * math.pi
ANGLE_INCREMENT = math.radians(0.5)


def room_scan(pose, sigma=0.005, seed=0):
    """Ranges (float32, as on the wire) of a scan of ROOM from a laser at pose."""
    x, y, th = pose
    rng = np.random.default_rng(seed)
    ranges = np.empty(BEAMS, dtype=np.float32)
    for i in range(BEAMS):
        phi = th + ANGLE_MIN + i * ANGLE_INCREMENT
        c, s = math.cos(phi), math.sin(phi)
        hits = [(rho - x * math.cos(b) - y * math.sin(b)) / (c * math.cos(b) + s * math.sin(b))
                for rho, b in ROOM if abs(c * math.cos(b) + s * math.sin(b)) > 1e-12]
        ranges[i] = min(t for t in hits if t > 0) + rng.normal(0, sigma)
    return ranges


def in_sensor_frame(wall, pose):
    """A world line (rho, beta) as (r, psi) seen from a sensor at pose."""
    rho, beta = wall
    c = rho - pose[0] * math.cos(beta) - pose[1] * math.sin(beta)
    psi = beta - pose[2] + (math.pi if c < 0 else 0.0)
    return abs(c), math.remainder(psi, math.tau)


def angle_diff(a, b):
    return math.remainder(a - b, math.tau)


def walls_seen(lines, pose):
    """Indices of the ROOM walls that some extracted line is (within 1 cm and 0.5°), sorted;
    fails if a line is none of them."""
    seen = set()
    for r, psi in lines.lines:
        near = [i for i, w in enumerate(ROOM)
                if abs(in_sensor_frame(w, pose)[0] - r) < 0.01
                and abs(angle_diff(in_sensor_frame(w, pose)[1], psi)) < math.radians(0.5)]
        assert len(near) == 1, (r, psi)
        seen.update(near)
    return sorted(seen)


POSE = (1.0, 0.5, 0.4)


@pytest.fixture(scope="module")
def room_map():
    return ekf_loc.LineMap(ROOM_SEGMENTS)


# ------------------------------------------------------------------------------ lines


def test_extract_lines_finds_the_four_walls_with_their_covariances():
    lines = ekf_loc.extract_lines(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT, 0.05, 30.0)
    assert len(lines) == 4
    assert lines.lines.shape == (4, 2) and lines.covariances.shape == (4, 2, 2)
    assert walls_seen(lines, POSE) == [0, 1, 2, 3]
    for cov in lines.covariances:
        assert np.allclose(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)
        # Below the 1 cm per-reading noise the extractor assumes: many points per line.
        assert 1e-4 < math.sqrt(cov[0, 0]) < 0.01 and math.sqrt(cov[1, 1]) < 3e-3
    assert np.all(lines.lengths > 1.5) and np.all(lines.num_points > 30)
    np.testing.assert_allclose(
        np.linalg.norm(lines.ends - lines.starts, axis=1), lines.lengths, rtol=1e-12
    )


def test_extract_lines_accepts_float64_lists_and_no_return_readings():
    ranges = room_scan(POSE)
    as32 = ekf_loc.extract_lines(ranges, ANGLE_MIN, ANGLE_INCREMENT)
    as64 = ekf_loc.extract_lines(ranges.astype(np.float64), ANGLE_MIN, ANGLE_INCREMENT)
    aslist = ekf_loc.extract_lines(ranges.tolist(), ANGLE_MIN, ANGLE_INCREMENT)
    assert np.array_equal(as32.lines, as64.lines) and np.array_equal(as32.lines, aslist.lines)
    # NaN and inf mean "no return" in a ROS LaserScan: skipped, not errors.
    holed = ranges.copy()
    holed[::40] = np.nan
    holed[20::40] = np.inf
    assert walls_seen(ekf_loc.extract_lines(holed, ANGLE_MIN, ANGLE_INCREMENT), POSE) == [
        0, 1, 2, 3
    ]
    assert len(ekf_loc.extract_lines(np.full(BEAMS, np.nan), ANGLE_MIN, ANGLE_INCREMENT)) == 0
    # Parameters: a minimum length longer than any wall leaves nothing.
    assert len(ekf_loc.extract_lines(ranges, ANGLE_MIN, ANGLE_INCREMENT,
                                     params={"min_length": 20.0})) == 0


def test_lines_round_trip_through_arrays():
    lines = ekf_loc.extract_lines(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT)
    copy = ekf_loc.Lines(lines.lines, lines.covariances, lines.starts, lines.ends,
                         lines.num_points)
    for name in ["lines", "covariances", "starts", "ends", "num_points"]:
        assert np.array_equal(getattr(copy, name), getattr(lines, name)), name


# -------------------------------------------------------------------------------- maps


def test_line_map_geometry_json_and_files(room_map, tmp_path):
    assert len(room_map) == 4 and room_map.frame_id == "map"
    for (rho, beta), (want_rho, want_beta) in zip(room_map.lines, ROOM):
        assert rho == pytest.approx(want_rho, abs=1e-12)
        assert abs(angle_diff(beta, want_beta)) < 1e-12
    path = tmp_path / "room.json"
    room_map.save(path)
    loaded = ekf_loc.LineMap.load(path)
    assert np.array_equal(loaded.segments, room_map.segments)
    assert json.loads(room_map.to_json())["format"] == "ekf-loc line map"
    assert np.array_equal(ekf_loc.LineMap.from_json(room_map.to_json()).lines, room_map.lines)
    aces = ekf_loc.LineMap.load(ACES_MAP)
    assert len(aces) == 321 and aces.segments.shape == (321, 2, 2)


def test_maps_from_one_scan_and_from_many(room_map):
    lines = ekf_loc.extract_lines(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT)
    first = ekf_loc.LineMap.from_scan(lines, POSE)
    assert len(first) == 4
    builder = ekf_loc.MapBuilder()
    for k, pose in enumerate([POSE, (2.0, 1.0, -0.3), (0.0, -0.5, 2.0)]):
        builder.add_scan(ekf_loc.extract_lines(room_scan(pose, seed=k), ANGLE_MIN,
                                               ANGLE_INCREMENT), pose)
    built = builder.finish()
    assert len(built) == 4  # three sightings of each wall fused into one
    for rho, beta in built.lines:
        assert any(abs(rho - r) < 0.02 and abs(angle_diff(beta, b)) < 0.01 for r, b in ROOM)


def test_map_build_from_log_equals_the_cli(ekf_bin, tmp_path):
    built, summary = ekf_loc.LineMap.build_from_log(ACES)
    out = tmp_path / "map.json"
    cli = run_ekf(ekf_bin, "map", "build", ACES, "--from-truth", "--out", out)
    assert summary == cli
    assert np.array_equal(built.segments, ekf_loc.LineMap.load(out).segments)


def test_map_build_slam_equals_the_cli(ekf_bin, tmp_path):
    built, trajectory, summary = ekf_loc.LineMap.build_slam(ACES)
    out, tum = tmp_path / "slam.json", tmp_path / "slam.tum"
    cli = run_ekf(ekf_bin, "map", "build", ACES, "--slam", "--out", out, "--tum", tum)
    for s in (summary, cli):
        s.pop("wall_time_s")
        s.pop("log")
    assert summary == cli
    assert summary["key_scans"] > 100 and summary["segments"] == len(built)
    assert np.array_equal(built.segments, ekf_loc.LineMap.load(out).segments)
    rows = np.loadtxt(tum)
    assert trajectory.shape == (len(rows), 4)
    assert np.allclose(trajectory[:, :3], rows[:, :3], atol=1e-9)


def test_import_grid_equals_the_cli(ekf_bin, tmp_path):
    yaml = tmp_path / "aces.yaml"
    run_ekf(ekf_bin, "map", "export-grid", ACES_MAP, "--out", yaml)
    imported, summary = ekf_loc.LineMap.import_grid(yaml, params={"scan_spacing": 2.0})
    out = tmp_path / "grid.json"
    cli = run_ekf(ekf_bin, "map", "import-grid", yaml, "--scan-spacing", "2.0", "--out", out)
    assert summary == cli
    assert len(imported) > 50
    assert np.array_equal(imported.segments, ekf_loc.LineMap.load(out).segments)
    with pytest.raises(ValueError, match="params: invalid type"):
        ekf_loc.LineMap.import_grid(yaml, params={"scan_spacing": "far"})


def test_replay_grow_map_returns_the_grown_map():
    first = ekf_loc.replay(ACES, mode="laser", init_from_truth=True)
    grown = ekf_loc.replay(ACES, mode="laser", init_from_truth=True, grow_map=True)
    assert len(first.map) < 20 < len(grown.map)


# ---------------------------------------------------------------- matching, Localizer


def test_match_lines_associates_each_wall(room_map):
    lines = ekf_loc.extract_lines(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT)
    cov = np.diag([1e-3, 1e-3, 1e-3])
    m = ekf_loc.match_lines(lines, room_map, POSE, cov)
    assert len(m) == 4 and m.rejected == []
    for obs, wall in zip(m.observed, m.map):
        r, psi = in_sensor_frame(ROOM[wall], POSE)
        assert lines.lines[obs][0] == pytest.approx(r, abs=0.01)
    assert np.all(m.nis < 9.21) and m.noise.shape == (4, 2, 2)
    # 1 m off in x with a small covariance: the walls across x no longer pass the gate.
    off = ekf_loc.match_lines(lines, room_map, (POSE[0] + 1, POSE[1], POSE[2]), cov)
    assert len(off) == 2 and {reason for _, reason in off.rejected} == {"outside gate"}


def test_localizer_fuses_a_scan_against_a_map(room_map):
    start = (POSE[0] + 0.05, POSE[1] - 0.05, POSE[2] + 0.02)
    loc = ekf_loc.Localizer(start, np.diag([0.01, 0.01, 0.003]), room_map)
    report = loc.update_scan(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT, 0.05, 30.0)
    assert report == {"extracted": 4, "matched": 4, "rejected": 0, "fused": 4,
                      "refused": 0, "merged": 0, "refitted": 0, "map_built": False}
    assert math.dist(loc.state[:2], POSE[:2]) < 0.01
    assert abs(angle_diff(loc.state[2], POSE[2])) < math.radians(0.3)
    assert len(loc.last_lines) == 4 and len(loc.last_fusions) == 4
    assert all(accepted for *_, accepted in loc.last_fusions)
    loc.predict_wheels(2.0, 2.0, 0.1)
    assert loc.state[0] > math.cos(POSE[2]) * 0.009 + POSE[0] - 0.01
    assert loc.update_compass(POSE[2]).accepted


def test_localizer_compass_recovers_from_a_gate_lock_out():
    # Believed good to 0.5 degrees, 8 degrees off: a 0.1-degree compass fails the gate
    # until the third consistent reading in a row is fused (compass.recover_after = 3).
    config = {"compass": {"variance": math.radians(0.1) ** 2}}
    loc = ekf_loc.Localizer((0.0, 0.0, 0.0), np.diag([1e-4, 1e-4, math.radians(0.5) ** 2]),
                            config=config)
    truth, updates = math.radians(8.0), []
    for _ in range(3):
        loc.predict_odometry(0.02, 0.02)
        truth += 0.02
        updates.append(loc.update_compass(truth))
    assert [(u.accepted, u.rejected_in_a_row, u.recovered) for u in updates] == [
        (False, 1, False), (False, 2, False), (True, 3, True)]
    assert abs(angle_diff(loc.state[2], truth)) < math.radians(0.2)
    assert "recovered=True" in repr(updates[2])


def test_localizer_does_not_fuse_a_compass_that_stands_still_while_the_robot_turns():
    # A 2-degree compass stuck at the start heading while odometry turns 0.1 rad a step:
    # once the turn is past the follow test's window (0.16 rad and the odometry's own
    # uncertainty) it is not fused, and stays so while it stays stuck.
    loc = ekf_loc.Localizer((0.0, 0.0, 0.0), np.diag([1e-4, 1e-4, 1e-4]))
    updates = []
    for _ in range(8):
        loc.predict_odometry(0.02, 0.1)
        updates.append(loc.update_compass(0.0, math.radians(2.0) ** 2))
    flags = [u.not_following for u in updates]
    assert flags[:2] == [False, False] and flags[-4:] == [True] * 4, flags
    assert flags == sorted(flags), flags
    assert not any(u.accepted for u in updates if u.not_following)
    assert "not_following=True" in repr(updates[-1])


def test_localizer_builds_its_map_from_the_first_scan():
    loc = ekf_loc.Localizer(POSE, np.eye(3) * 1e-4)
    assert len(loc.line_map) == 0
    report = loc.update_scan(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT)
    assert report["map_built"] and len(loc.line_map) == 4
    assert loc.update_scan(room_scan(POSE, seed=1), ANGLE_MIN, ANGLE_INCREMENT)["fused"] == 4


# ----------------------------------------------------------------------------- replay


def tum_rows(path):
    """(t_ns, x, y, theta) of each row of a TUM file, the heading from its quaternion."""
    rows = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("#"):
            continue
        t, x, y, _, _, _, qz, qw = line.split()
        qz, qw = float(qz), float(qw)
        theta = math.atan2(2 * qz * qw, 1 - 2 * qz * qz)
        rows.append((int(Decimal(t) * 10**9), float(x), float(y), theta))
    return rows


def test_replay_with_global_localization_finds_the_robot_and_agrees_with_the_cli(ekf_bin, tmp_path):
    # Started 1 km off and a quarter turn wrong: only the map search can put it right.
    config = {"initial": {"x": 1000.0, "y": 1000.0, "theta": math.pi / 2}}
    toml = tmp_path / "far.toml"
    toml.write_text("[initial]\nx = 1000.0\ny = 1000.0\ntheta = 1.5707963267948966\n")
    result = ekf_loc.replay(ACES, config=config, mode="laser", map=ACES_MAP,
                            global_localization=True)
    tracking = result.summary["tracking"]
    assert 1 <= tracking["locked_on_scan"] <= 20
    assert result.summary["accuracy"]["share_over_1m"] <= 0.05
    cli = run_ekf(ekf_bin, "replay", ACES, "--map", ACES_MAP, "--mode", "laser",
                  "--global", "--config", toml)
    assert cli["tracking"] == tracking
    with pytest.raises(ValueError, match="--global needs a map"):
        ekf_loc.replay(ACES, mode="laser", global_localization=True)


@pytest.mark.parametrize("mode", ["laser+compass", "odometry"])
def test_replay_returns_the_poses_of_ekf_replay_tum(ekf_bin, tmp_path, mode):
    tum = tmp_path / "cli.tum"
    cli = run_ekf(ekf_bin, "replay", ACES, "--map", ACES_MAP, "--mode", mode,
                  "--init-from-truth", "--tum", tum)
    result = ekf_loc.replay(ACES, mode=mode, map=ACES_MAP, init_from_truth=True)
    rows = tum_rows(tum)
    assert len(rows) == len(result.x) == cli["poses_written"] > 7000
    assert [r[0] for r in rows] == result.t_ns.tolist()
    assert [r[1] for r in rows] == result.x.tolist()  # the TUM text round-trips exactly
    assert [r[2] for r in rows] == result.y.tolist()
    theta_err = [angle_diff(r[3], th) for r, th in zip(rows, result.theta)]
    assert max(map(abs, theta_err)) < 1e-12
    np.testing.assert_allclose(result.t, result.t_ns * 1e-9, rtol=1e-15)
    # The same summary, but for the measured times.
    for key in ["wall_time_s", "timings"]:
        cli.pop(key)
        result.summary.pop(key)
    assert result.summary == cli
    cov = result.covariance
    assert cov.shape == (len(rows), 3, 3)
    assert np.allclose(cov, cov.transpose(0, 2, 1)) and np.all(np.linalg.eigvalsh(cov) > 0)
    assert len(result.reference_x) == cli["messages_read"]["/ground_truth"]


def test_replay_config_from_file_and_dict(ekf_bin, tmp_path):
    toml = tmp_path / "robot.toml"
    toml.write_text("[initial]\nsigma_theta = 0.2\n")
    by_file = ekf_loc.replay(ACES, config=toml, mode="compass", init_from_truth=True)
    by_dict = ekf_loc.replay(ACES, config={"initial": {"sigma_theta": 0.2}},
                             mode="compass", init_from_truth=True)
    default = ekf_loc.replay(ACES, mode="compass", init_from_truth=True)
    assert np.array_equal(by_file.x, by_dict.x)
    assert not np.array_equal(by_file.x, default.x)


def test_simulate_writes_the_bytes_of_ekf_simulate_and_returns_the_truth(ekf_bin, tmp_path):
    cli_log, py_log = tmp_path / "cli.mcap", tmp_path / "py.mcap"
    cli = run_ekf(ekf_bin, "simulate", "paper", "--duration", "20", "--seed", "3",
                  "--out", cli_log)
    run = ekf_loc.simulate("paper", out=py_log, seed=3, duration=20)
    assert py_log.read_bytes() == cli_log.read_bytes()
    assert len(run.t) == len(run.x) == cli["stats"]["steps"] + 1 == 201
    np.testing.assert_allclose(run.t[:3], [0.0, 0.1, 0.2], atol=1e-12)
    for key in ["out"]:
        cli.pop(key)
        run.summary.pop(key)
    assert run.summary == cli
    # The paper scenario starts on its first edge at (2, 1) heading east, 1 m from the
    # walls' loop, and drives at 0.3 m/s.
    assert (run.x[0], run.y[0], run.theta[0]) == (2.0, 1.0, 0.0)
    assert 5.0 < cli["stats"]["distance_m"] < 6.5
    assert run.estimate_x.size == run.nees.size == run.nees_heading.size == 0
    assert np.all(run.path_deviation < 0.15)


def test_simulate_with_the_ekf_in_the_loop_reports_its_estimate_and_nees():
    run = ekf_loc.simulate("paper", duration=30, steer_by="ekf")
    err = np.hypot(run.estimate_x - run.x, run.estimate_y - run.y)
    assert err.shape == run.nees.shape == (301,)
    assert np.sqrt(np.mean(err ** 2)) < 0.02
    assert np.all(np.isfinite(run.nees)) and 0.5 < run.nees.mean() < 10
    # The parts: the heading's NEES is e_theta^2 / P_theta_theta, and with the position
    # and heading nearly uncorrelated the whole is close to the sum of its parts.
    assert run.nees_position.shape == run.nees_heading.shape == (301,)
    assert np.all(run.nees_position <= run.nees + 1e-9)
    assert np.all(run.nees_heading <= run.nees + 1e-9)
    assert abs(np.mean(run.nees_position + run.nees_heading) / run.nees.mean() - 1) < 0.2


# ------------------------------------------------------------------------------ errors

F = ekf_loc.Filter
ONE_LINE = ([[3.0, 0.1]], [[[1e-4, 0], [0, 1e-4]]], [[3.0, 0.0]])

ERRORS = [
    # (call, exception, message)
    (lambda: F().predict_wheels(math.nan, 1.0, 0.1), ValueError,
     "left wheel speed is not finite (NaN or infinite)"),
    (lambda: F().predict_wheels(1.0, 1.0, 0.0), ValueError, "dt is out of range: expected > 0"),
    (lambda: F().predict_odometry(0.1, math.inf), ValueError,
     "motion dtheta is not finite (NaN or infinite)"),
    (lambda: F().update_compass(0.1, -1.0), ValueError,
     "compass variance is negative; a variance must be ≥ 0"),
    (lambda: F(pose=(0, 0)), ValueError, "pose: expected shape (3,) as (x, y, theta), got (2,)"),
    (lambda: ekf_loc.simulate("moon"), ValueError, 'unknown scenario "moon"'),
    (lambda: ekf_loc.simulate("paper", steer_by="luck"), ValueError,
     'steer_by: expected one of truth, ekf, odometry, got "luck"'),
    (lambda: ekf_loc.simulate("paper", resolution=0.3), ValueError, "--resolution"),
    (lambda: ekf_loc.simulate("missing.json"), FileNotFoundError, "missing.json"),
    (lambda: F(covariance=np.ones((3, 3))), ValueError,
     "initial covariance is not positive definite"),
    (lambda: F(covariance=np.full((3, 3), np.nan)), ValueError,
     "covariance[0, 0] is NaN; expected a finite number"),
    (lambda: F(config={"robot": {"wheel_radius": -1, "track": 0.6}}), ValueError,
     "invalid config: robot.wheel_radius: expected a finite number > 0, found -1"),
    (lambda: F(config={"robt": {}}), ValueError, "config: unknown field `robt`"),
    (lambda: F(config="robot.toml"), TypeError, "config: expected a dict or None"),
    (lambda: F().update_lines([[3.0, np.nan]], *ONE_LINE[1:]), ValueError,
     "observed[0, 1] is NaN; expected a finite number"),
    (lambda: F().update_lines(np.zeros((2, 3)), *ONE_LINE[1:]), ValueError,
     "observed: expected shape (N, 2) as (r, psi), got (2, 3)"),
    (lambda: F().update_lines(ONE_LINE[0], np.eye(2), ONE_LINE[2]), ValueError,
     "covariances: expected a 3-dimensional array, got shape (2, 2)"),
    (lambda: F().update_lines(ONE_LINE[0], ONE_LINE[1], [[3.0, 0.0], [1.0, 0.0]]), ValueError,
     "map_lines: expected 1 rows (one per row of observed), got 2"),
    (lambda: F().update_lines(np.array([[3 + 0j, 0]]), *ONE_LINE[1:]), TypeError,
     "observed: expected real numbers (a float or integer dtype), got dtype complex128"),
    (lambda: F().update_lines([["3", "0"]], *ONE_LINE[1:]), TypeError,
     "observed: expected real numbers (a float or integer dtype), got dtype <U1"),
    (lambda: F().update_lines(ONE_LINE[0], [[[1e-4, 1], [0, 1e-4]]], ONE_LINE[2]), ValueError,
     "line 0: line covariance is not symmetric"),
    (lambda: F().run(wheels=np.ones((3, 2))), ValueError,
     "wheels: expected shape (N, 3) as (left, right, dt), got (3, 2)"),
    (lambda: F().run(wheels=[[1, 1, 0.1]], odometry=[[0.1, 0]]), ValueError,
     "give exactly one of wheels= (N, 3) or odometry= (N, 2)"),
    (lambda: F().run(wheels=[[1, 1, 0.1], [1, np.nan, 0.1]]), ValueError,
     "step 1: right wheel speed is not finite (NaN or infinite)"),
    (lambda: F().run(wheels=np.ones((2, 3)), compass=[0.0]), ValueError,
     "compass: expected 2 rows (one per row of the motion), got 1"),
    (lambda: F().run(wheels=np.ones((1, 3)), compass=[0.0], compass_mask=[1]), TypeError,
     "compass_mask: expected a 1-dimensional bool array"),
    (lambda: F().run(wheels=np.ones((1, 3)), line_observed=np.ones((1, 1, 2))), ValueError,
     "lines need all of line_observed=, line_covariances= and line_map="),
    (lambda: F().run(wheels=np.ones((1, 3)), line_observed=np.ones((1, 1, 2)),
                     line_covariances=np.ones((1, 1, 2, 2)), line_map=np.ones((1, 1, 2)),
                     line_counts=[2]), ValueError,
     "line_counts[0] is 2; expected a whole number from 0 to 1 (K)"),
    (lambda: ekf_loc.extract_lines(np.ones(10), 0.0, 0.0), ValueError,
     "invalid laser scan: angle_increment must be a finite, non-zero angle (rad)"),
    (lambda: ekf_loc.extract_lines(np.ones((2, 5)), 0.0, 0.1), ValueError,
     "ranges: expected a 1-dimensional array, got shape (2, 5)"),
    (lambda: ekf_loc.extract_lines(np.ones(10), 0.0, 0.1, params={"min_points": 1}), ValueError,
     "invalid line extraction parameter: min_points must be at least 2"),
    (lambda: ekf_loc.LineMap([[[0, 0], [0, 0]]]), ValueError,
     "segments[0]: segment length is out of range: expected > 0 (distinct end points)"),
    (lambda: ekf_loc.LineMap.load("/no/such/map.json"), FileNotFoundError,
     "/no/such/map.json: No such file or directory (os error 2)"),
    (lambda: ekf_loc.LineMap.from_json('{"format": "ekf-loc line map", "version": 1, '
                                       '"segments": [{"start": [0, 0]}]}'),
     ValueError, "segments[0]"),
    (lambda: ekf_loc.replay("/no/such/log.mcap"), FileNotFoundError,
     "/no/such/log.mcap: cannot open: No such file or directory (os error 2)"),
    (lambda: ekf_loc.replay(ACES, map="/no/such/map.json"), FileNotFoundError,
     "/no/such/map.json: No such file or directory (os error 2)"),
    (lambda: ekf_loc.replay(ACES, mode="gps"), ValueError,
     'mode: expected one of odometry, compass, laser, laser+compass, got "gps"'),
    (lambda: ekf_loc.replay(ACES, config="/no/such/robot.toml"), FileNotFoundError,
     "/no/such/robot.toml: No such file or directory (os error 2)"),
    (lambda: ekf_loc.replay(ACES, config={"initial": {"sigma_xy": -1}}), ValueError,
     "config: initial.sigma_xy: expected a finite number > 0, found -1"),
    (lambda: ekf_loc.replay(ROOT / "testdata" / "aces-map.json"), ValueError,
     "aces-map.json"),
]


@pytest.mark.parametrize("call, exception, message", ERRORS,
                         ids=[f"{i}" for i in range(len(ERRORS))])
def test_bad_input_raises_a_clear_exception(call, exception, message):
    with pytest.raises(exception) as info:
        call()
    assert message in str(info.value)


def test_a_failed_update_leaves_the_filter_unchanged():
    f = F((1.0, 2.0, 0.3), np.eye(3) * 1e-3)
    f.predict_wheels(2.0, 2.5, 0.1)
    state, cov, counts = f.state, f.covariance, f.counts
    good = [3.0, 0.1]
    with pytest.raises(ValueError, match="line 1: line covariance is not positive definite"):
        f.update_lines([good, good], [np.eye(2) * 1e-4, [[1, 2], [2, 1]]], [[3, 0], [3, 0]])
    with pytest.raises(ValueError, match="step 2"):
        f.run(wheels=[[1, 1, 0.1], [1, 1, 0.1], [1, 1, -0.1]])
    assert np.array_equal(f.state, state) and np.array_equal(f.covariance, cov)
    assert f.counts == counts


# ------------------------------------------------------------ state and covariance


def test_state_and_covariance_can_be_assigned_like_filterpys_x_and_p():
    f = F((1.0, 2.0, 0.3), np.eye(3) * 1e-3)
    f.predict_wheels(2.0, 2.5, 0.1)
    cov, counts = f.covariance, f.counts
    f.state = [4.0, -1.0, 4.0]  # theta wrapped; the covariance kept
    assert f.state.tolist() == [4.0, -1.0, 4.0 - 2 * math.pi]
    assert np.array_equal(f.covariance, cov)
    p = np.array([[2e-3, 1e-4, 0.0], [1e-4, 3e-3, -2e-4], [0.0, -2e-4, 1e-3]])
    f.covariance = p  # the state kept
    assert np.array_equal(f.covariance, p)
    assert f.state.tolist() == [4.0, -1.0, 4.0 - 2 * math.pi]
    # Round-off asymmetry (here 3e-10 of the largest entry) is symmetrised, from any
    # array-like.
    skew = p.copy()
    skew[0, 1] += 1e-12
    f.covariance = skew.tolist()
    assert np.array_equal(f.covariance, (skew + skew.T) / 2)
    assert f.covariance[0, 1] != p[0, 1]
    # Reading gives copies: changing them changes nothing.
    f.state[0] = 99.0
    f.covariance[0, 0] = 99.0
    assert f.state[0] == 4.0 and f.covariance[0, 0] == 2e-3
    assert f.counts == counts
    # Then it is the filter made with that state and covariance, bit for bit.
    g = F((4.0, -1.0, 4.0), (skew + skew.T) / 2)
    for filt in (f, g):
        filt.predict_wheels(2.0, 2.5, 0.1)
        filt.update_compass(-2.2)
        filt.update_lines(*ONE_LINE)
    assert f.state.tobytes() == g.state.tobytes()
    assert f.covariance.tobytes() == g.covariance.tobytes()


ASYMMETRIC = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) * 1e-3
SETTER_ERRORS = [
    # (attribute, value, exception, the whole message)
    ("state", (1.0, 2.0), ValueError, "state: expected shape (3,) as (x, y, theta), got (2,)"),
    ("state", (1.0, math.nan, 0.0), ValueError, "state[1] is NaN; expected a finite number"),
    ("state", [[1.0, 2.0, 0.3]], ValueError,
     "state: expected a 1-dimensional array, got shape (1, 3)"),
    ("state", "north", TypeError,
     "state: expected real numbers (a float or integer dtype), got dtype <U5"),
    ("covariance", np.eye(2), ValueError, "covariance: expected shape (3, 3), got (2, 2)"),
    ("covariance", [[1e-3, 0, 0], [0, 1e-3, math.inf], [0, 0, 1e-3]], ValueError,
     "covariance[1, 2] is inf; expected a finite number"),
    ("covariance", ASYMMETRIC, ValueError,
     "covariance: expected a symmetric matrix (to a relative tolerance of 1.5e-8), "
     "got covariance[0, 1] = 0.0005 and covariance[1, 0] = 0"),
    ("covariance", np.diag([1e-3, -1e-3, 2e-3]), ValueError,
     "covariance: expected a positive definite matrix, "
     "got eigenvalues -1.000e-03, 1.000e-03, 2.000e-03"),
    ("covariance", np.zeros((3, 3)), ValueError,
     "covariance: expected a positive definite matrix, "
     "got eigenvalues 0.000e+00, 0.000e+00, 0.000e+00"),
]


@pytest.mark.parametrize("name, value, exception, message", SETTER_ERRORS,
                         ids=[f"{e[0]}-{i}" for i, e in enumerate(SETTER_ERRORS)])
def test_assigning_a_bad_state_or_covariance_raises_and_changes_nothing(
        name, value, exception, message):
    f = F((1.0, 2.0, 0.3), np.eye(3) * 1e-3)
    with pytest.raises(exception) as info:
        setattr(f, name, value)
    assert str(info.value) == message
    assert f.state.tolist() == [1.0, 2.0, 0.3]
    assert np.array_equal(f.covariance, np.eye(3) * 1e-3)


def test_a_bad_pickled_state_is_refused_with_a_clear_message():
    f = F((1.0, 2.0, 0.3), np.eye(3) * 1e-3)
    good = f.__getstate__()
    assert good["state"] == [1.0, 2.0, 0.3] and good["version"] == 1
    cases = [
        (dict(good, version=2), ValueError,
         "Filter state: version 2 is not supported (this ekf_loc reads version 1)"),
        ({k: v for k, v in good.items() if k != "counts"}, ValueError,
         'Filter state: missing "counts"'),
        (dict(good, robot=[0.05]), ValueError, 'Filter state: "robot": expected 2 floats'),
        (dict(good, covariance=[[1, 0, 0], [0, -1, 0], [0, 0, 1]]), ValueError,
         "Filter state: covariance is not positive definite"),
        (dict(good, state=[0.0, math.inf, 0.0]), ValueError,
         "Filter state: state is not finite (NaN or infinite)"),
        (dict(good, robot=[0.05, 0.0]), ValueError,
         "Filter state: track is out of range: expected > 0"),
        (dict(good, line_gate=-1.0), ValueError,
         "Filter state: gate threshold is out of range: expected a finite number > 0"),
        ([1, 2], TypeError, "Filter state: expected a dict from Filter.__getstate__, got list"),
    ]
    for state, exception, message in cases:
        with pytest.raises(exception) as info:
            f.__setstate__(state)
        assert str(info.value) == message
    assert f.__getstate__() == good


# ----------------------------------------------------------------------------- example


def test_example_replays_and_plots(tmp_path):
    out = tmp_path / "aces.png"
    script = ROOT / "crates" / "ekf-py" / "examples" / "replay_plot.py"
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, script, "--out", out], capture_output=True,
                          text=True, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20_000
    assert "position RMSE" in proc.stdout


# ------------------------------------------------------------------------------- stubs


def test_type_stubs_match_the_module(tmp_path):
    """mypy's stubtest compares every name, signature and default of the .pyi stubs with
    the compiled module (run in a temporary folder, where it leaves its cache)."""
    proc = subprocess.run([sys.executable, "-m", "mypy.stubtest", "ekf_loc"],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    package = Path(ekf_loc.__file__).parent
    assert (package / "py.typed").is_file() and (package / "_ekf_loc.pyi").is_file()


def garbage(rng):
    """A random array-like: 0 to 4 dimensions of 0 to 4 entries, with NaN, inf, huge,
    negative and integer values, sometimes of a wrong dtype or not an array at all."""
    shape = tuple(rng.integers(0, 5, size=rng.integers(0, 5)))
    values = rng.choice([0.0, 1.0, -1.0, 1e-300, 1e308, -1e308, np.nan, np.inf, 3.5, 1e-4],
                        size=shape)
    kind = rng.integers(0, 8)
    with np.errstate(all="ignore"):  # casting 1e308 to float32 or int64 is the point
        if kind == 0:
            return values.astype(np.float32)
        if kind == 1:
            return values.astype(complex)
        if kind == 2:
            return values.tolist()
        if kind == 3:
            return "not an array"
        if kind == 4:
            return np.nan_to_num(values).astype(np.int64)
    return values


def test_no_input_makes_rust_panic():
    """Random arrays of any shape and value into every array-taking call raise ValueError
    or TypeError (or succeed), never pyo3's PanicException (a BaseException)."""
    rng = np.random.default_rng(1)
    room = ekf_loc.LineMap(ROOM_SEGMENTS)
    lines = ekf_loc.extract_lines(room_scan(POSE), ANGLE_MIN, ANGLE_INCREMENT)
    calls = [
        lambda g: F(g(), g()),
        lambda g: setattr(F(), "state", g()),
        lambda g: setattr(F(), "covariance", g()),
        lambda g: F().update_lines(g(), g(), g()),
        lambda g: F().run(wheels=g(), compass=g()),
        lambda g: F().run(odometry=g(), line_observed=g(), line_covariances=g(),
                          line_map=g(), line_counts=g()),
        lambda g: ekf_loc.extract_lines(g(), *rng.choice([0.0, 0.01, np.nan, 1e300], 2)),
        lambda g: ekf_loc.Lines(g(), g(), g(), g(), g()),
        lambda g: ekf_loc.LineMap(g()),
        lambda g: ekf_loc.match_lines(lines, room, g(), g(), g()),
        lambda g: ekf_loc.Localizer(POSE, np.eye(3) * 1e-3, room).update_scan(g(), 0.0, 0.01),
        lambda g: ekf_loc.MapBuilder().add_scan(lines, g()),
    ]
    outcomes = {"ok": 0, "error": 0}
    for _ in range(300):
        for call in calls:
            try:
                call(lambda: garbage(rng))
                outcomes["ok"] += 1
            except (ValueError, TypeError):
                outcomes["error"] += 1
    assert outcomes["ok"] > 0 and outcomes["error"] > 0
