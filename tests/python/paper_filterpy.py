"""The paper's EKF written on FilterPy (an implementation we did not write), and a
scenario to run it and ekf_loc on.

Model (Hoang et al., eqs. 1-19, with the errata of docs/ERRATA.md fixed), written out
here from the equations, not from ekf-core:

- motion: ds_{L,R} = dt R w_{L,R}, ds = (ds_L + ds_R)/2, dth = (ds_R - ds_L)/L; the pose
  advances ds along the mid-angle th + dth/2, then turns by dth;
- process noise W Q W^T with W = df/d(w_R, w_L) and Q = diag(delta w_R^2 + floor,
  delta w_L^2 + floor);
- compass: h(x) = th, residual wrapped;
- laser line (r, psi) of map line (rho, beta), laser mounted at (mx, my, mth) on the robot:
  sensor pose s = x (+) mount, C = rho - x_s cos(beta) - y_s sin(beta), r = |C|,
  psi = beta - th_s (+ pi if C < 0), residual of psi wrapped.

FilterPy's ExtendedKalmanFilter.update is already the Joseph form
P = (I-KH) P (I-KH)^T + K R K^T, as ekf-core's; ekf-core also symmetrises P, which changes
it only by round-off. The heading is wrapped after every step, as ekf-core's state is.
Gating: a measurement whose NIS (from FilterPy's own y and S) exceeds the chi-square
quantile is undone, as ekf-core leaves the state unchanged.
"""

import copy
import math

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from scipy.stats import chi2

# The paper's robot and the defaults of ekf_loc (LocalizerConfig::default()).
WHEEL_RADIUS = 0.05
TRACK = 0.60
DELTA = 0.01
FLOOR = 1.296e-3
MOUNT = (0.2, 0.05, -math.pi / 2)  # the paper's SICK: 0 deg to the robot's right
GATE_PROBABILITY = 0.99

# A 10 m x 6 m room: (rho, beta) of its four walls in the world frame.
WALLS = np.array([(0.5, math.pi), (10.0, 0.0), (0.5, -math.pi / 2), (6.0, math.pi / 2)])


def wrap(a):
    """An angle wrapped to (-pi, pi]."""
    w = math.remainder(a, math.tau)
    return math.pi if w == -math.pi else w


def config():
    """The ekf_loc config dict of this model."""
    return {
        "robot": {"wheel_radius": WHEEL_RADIUS, "track": TRACK},
        "wheel_noise": {"delta": DELTA, "floor": FLOOR},
        "laser_mount": {"x": MOUNT[0], "y": MOUNT[1], "theta": MOUNT[2]},
        "compass": {"variance": 0.02**2, "gate_probability": GATE_PROBABILITY},
        "matching": {"gate_probability": GATE_PROBABILITY},
    }


def motion(x, left, right, dt):
    """f(x, u) and its Jacobians A = df/dx and W = df/d(w_R, w_L)."""
    ds_l, ds_r = dt * WHEEL_RADIUS * left, dt * WHEEL_RADIUS * right
    ds, dth = (ds_l + ds_r) / 2, (ds_r - ds_l) / TRACK
    m = x[2] + dth / 2
    c, s = math.cos(m), math.sin(m)
    nxt = np.array([x[0] + ds * c, x[1] + ds * s, wrap(x[2] + dth)])
    a = np.array([[1.0, 0.0, -ds * s], [0.0, 1.0, ds * c], [0.0, 0.0, 1.0]])
    half, turn = dt * WHEEL_RADIUS / 2, dt * WHEEL_RADIUS / TRACK
    w = np.array(
        [
            [half * c - ds * s * turn / 2, half * c + ds * s * turn / 2],
            [half * s + ds * c * turn / 2, half * s - ds * c * turn / 2],
            [turn, -turn],
        ]
    )
    return nxt, a, w


def sensor_pose(x):
    """The laser's pose x (+) mount, and d(x_s, y_s)/d(th)."""
    c, s = math.cos(x[2]), math.sin(x[2])
    mx, my, mth = MOUNT
    pose = (x[0] + c * mx - s * my, x[1] + s * mx + c * my, x[2] + mth)
    return pose, (-s * mx - c * my, c * mx - s * my)


def line_h(x, wall):
    """h(x) = (r, psi) of a map line seen from state x."""
    (xs, ys, ths), _ = sensor_pose(x)
    rho, beta = wall
    c = rho - xs * math.cos(beta) - ys * math.sin(beta)
    psi = beta - ths + (math.pi if c < 0 else 0.0)
    return np.array([abs(c), wrap(psi)])


def line_jacobian(x, wall):
    """H = dh/dx of line_h (docs/ERRATA.md 2: dr/d(x, y) = -sign(C) (cos b, sin b))."""
    (xs, ys, _), (dxs, dys) = sensor_pose(x)
    rho, beta = wall
    cb, sb = math.cos(beta), math.sin(beta)
    sign = -1.0 if rho - xs * cb - ys * sb < 0 else 1.0
    dc_dth = -(dxs * cb + dys * sb)
    return np.array([[-sign * cb, -sign * sb, sign * dc_dth], [0.0, 0.0, -1.0]])


def line_residual(z, h):
    return np.array([z[0] - h[0], wrap(z[1] - h[1])])


def compass_residual(z, h):
    return np.array([wrap(z[0] - h[0])])


class PaperEKF(ExtendedKalmanFilter):
    """FilterPy's EKF with the paper's motion model and optional chi-square gates."""

    def __init__(self, x0, p0, gating=True):
        super().__init__(dim_x=3, dim_z=1)
        self.x = np.array(x0, dtype=float)
        self.P = np.array(p0, dtype=float)
        self._speeds = (0.0, 0.0, 0.0)
        self.gate1 = chi2.ppf(GATE_PROBABILITY, 1) if gating else math.inf
        self.gate2 = chi2.ppf(GATE_PROBABILITY, 2) if gating else math.inf

    def predict_x(self, u=0):
        self.x = motion(self.x, *self._speeds)[0]

    def predict_wheels(self, left, right, dt):
        self._speeds = (left, right, dt)
        _, self.F, w = motion(self.x, left, right, dt)
        q = np.diag([DELTA * right**2 + FLOOR, DELTA * left**2 + FLOOR])
        self.Q = w @ q @ w.T
        self.predict()

    def _gated_update(self, z, jacobian, hx, r, residual, gate):
        """FilterPy's update; undone if its NIS y^T S^-1 y exceeds the gate."""
        before = (self.x.copy(), self.P.copy())
        self.update(z, jacobian, hx, R=r, residual=residual)
        nis = float(self.y @ np.linalg.solve(self.S, self.y))
        if nis > gate:
            self.x, self.P = before
            return False, nis
        self.x[2] = wrap(self.x[2])
        return True, nis

    def update_compass(self, heading, variance):
        return self._gated_update(
            np.array([heading]),
            lambda x: np.array([[0.0, 0.0, 1.0]]),
            lambda x: np.array([x[2]]),
            np.array([[variance]]),
            compass_residual,
            self.gate1,
        )

    def update_line(self, z, r, wall):
        return self._gated_update(
            np.asarray(z),
            lambda x: line_jacobian(x, wall),
            lambda x: line_h(x, wall),
            np.asarray(r),
            line_residual,
            self.gate2,
        )

    def copy(self):
        return copy.deepcopy(self)


def make_scenario(steps, seed=7, lines_every=1, outlier_every=0):
    """A drive through the room: per step wheel speeds (N, 3), a compass heading (N,),
    and the four walls seen from the true pose with noise: observed (N, 4, 2),
    covariances (N, 4, 2, 2), map lines (N, 4, 2), and how many lines each step uses (N,)
    (4 every `lines_every` steps, else 0). Every `outlier_every`-th heading is 1 rad off
    (to exercise the gate)."""
    rng = np.random.default_rng(seed)
    truth = np.array([4.0, 2.5, 0.3])
    wheels = np.empty((steps, 3))
    compass = np.empty(steps)
    observed = np.empty((steps, len(WALLS), 2))
    covariances = np.empty((steps, len(WALLS), 2, 2))
    cov = np.array([[4e-4, 1e-5], [1e-5, 2e-4]])
    chol = np.linalg.cholesky(cov)
    for k in range(steps):
        # Drive forward and turn gently, turning harder near the walls.
        x, y = truth[0], truth[1]
        near = min(x - 0.5, 10.0 - x, y - 0.5, 6.0 - y) < 1.2
        turn = 1.5 if near else 0.3 * math.sin(0.05 * k)
        left, right = 3.0 - turn + rng.normal(0, 0.1), 3.0 + turn + rng.normal(0, 0.1)
        wheels[k] = (left, right, 0.1)
        truth = motion(truth, left, right, 0.1)[0]
        compass[k] = wrap(truth[2] + rng.normal(0, 0.02))
        if outlier_every and k % outlier_every == outlier_every - 1:
            compass[k] = wrap(compass[k] + 1.0)
        for j, wall in enumerate(WALLS):
            observed[k, j] = line_h(truth, wall) + chol @ rng.normal(size=2)
            covariances[k, j] = cov
    counts = np.where(np.arange(steps) % lines_every == 0, len(WALLS), 0)
    map_lines = np.broadcast_to(WALLS, observed.shape).copy()
    return wheels, compass, observed, covariances, map_lines, counts
