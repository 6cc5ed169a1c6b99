"""Type stubs of the native module ekf_loc._ekf_loc (re-exported by ekf_loc).

Units and conventions (ROS REP-103): metres, radians, seconds; world x east, y north;
robot x forward, y left; headings counter-clockwise, wrapped to (-pi, pi]; poses
``(x, y, theta)``, covariances 3x3 in that order. Array arguments accept any array-like
of real numbers (converted to float64); results are float64 numpy arrays unless stated.
"""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt
from typing_extensions import TypeAlias

__version__: str
_debug_build: bool  # True for an unoptimised build (benchmarks refuse it)
__all__ = [
    "BatchResult",
    "CompassUpdate",
    "Filter",
    "LineMap",
    "LineUpdates",
    "Lines",
    "Localizer",
    "MapBuilder",
    "Matches",
    "ReplayResult",
    "SimulationResult",
    "TimedLocalizer",
    "UpdateOutcome",
    "__version__",
    "extract_lines",
    "match_lines",
    "replay",
    "simulate",
]

_ArrayLike: TypeAlias = npt.ArrayLike
_F64Array: TypeAlias = npt.NDArray[np.float64]
_BoolArray: TypeAlias = npt.NDArray[np.bool_]
_U64Array: TypeAlias = npt.NDArray[np.uint64]
_Pose: TypeAlias = Union[Tuple[float, float, float], Sequence[float], npt.NDArray[np.floating]]
_PathLike: TypeAlias = Union[str, "os.PathLike[str]"]
_ConfigDict: TypeAlias = Mapping[str, Any]
_ReplayMode: TypeAlias = Literal["odometry", "compass", "laser", "laser+compass"]
_SteerBy: TypeAlias = Literal["truth", "ekf", "odometry"]

@final
class UpdateOutcome:
    """The outcome of one update, with FilterPy's names for the innovation ``y``, its
    covariance ``S`` and the gain ``K``.

    ``y = z - h(x)`` (wrapped) and ``S = H P H^T + R`` are at the state before the update,
    whether or not the gate let the measurement through. ``K = P H^T S^-1`` is the gain
    that was applied: zeros if the gate refused the measurement, so ``x+ = x- + K y``
    holds either way (up to the wrapping of theta)."""

    @property
    def accepted(self) -> bool:
        """True if the measurement passed its chi-square gate and was fused; False if it
        was refused and the state left unchanged."""
    @property
    def nis(self) -> float:
        """Normalised innovation squared y^T S^-1 y (chi-square, dof = measurement size)."""
    @property
    def y(self) -> _F64Array:
        """(1,) innovation z - h(x) (rad, wrapped), at the state before the update."""
    @property
    def S(self) -> _F64Array:
        """(1, 1) innovation covariance H P H^T + R (rad^2), at the state before the update."""
    @property
    def K(self) -> _F64Array:
        """(3, 1) gain P H^T S^-1 that was applied; zeros if the gate refused the update."""

@final
class CompassUpdate:
    """What ``Localizer.update_compass`` did with a heading."""

    @property
    def accepted(self) -> bool:
        """True if fused: through the gate, or as the recovery from a gate lock-out."""
    @property
    def nis(self) -> float:
        """Normalised innovation squared at the predicted state (chi-square, 1 dof)."""
    @property
    def rejected_in_a_row(self) -> int:
        """Consecutive headings up to this one that failed the gate, each agreeing with
        the one before once odometry's turn is taken out; 0 if this one passed."""
    @property
    def recovered(self) -> bool:
        """True if it failed the gate but was fused because ``rejected_in_a_row``
        reached the config's ``compass.recover_after``."""
    @property
    def refused_by_laser(self) -> bool:
        """True if ``rejected_in_a_row`` reached ``recover_after`` but the laser refused
        the recovery: the last scan's lines fit the filter's heading better."""
    @property
    def not_following(self) -> bool:
        """True if not fused because the compass stood still while the robot turned."""

@final
class LineUpdates:
    """The outcomes of a sequence of line updates, one entry per line, in order.

    The lines are fused one after the other, each at the state the lines before it left,
    so ``y``, ``S`` and ``K`` are per line, as ``nis`` is: line i's own innovation, its
    covariance and gain at the state it was fused into, exactly what FilterPy's ``update``
    leaves in ``y``, ``S`` and ``K`` when called once per line. They are not the blocks of
    one stacked 2N-row update (whose gain comes from the covariance before all the lines).
    A refused line has ``K`` zeros (nothing applied), and ``y``, ``S`` at the state it was
    offered to."""

    @property
    def nis(self) -> _F64Array:
        """(N,) NIS of each line at the state it was fused into."""
    @property
    def accepted(self) -> _BoolArray:
        """(N,) whether each line passed the gate and was fused."""
    @property
    def y(self) -> _F64Array:
        """(N, 2) innovation (r, psi) of each line (m, rad; psi wrapped)."""
    @property
    def S(self) -> _F64Array:
        """(N, 2, 2) innovation covariance H P H^T + R of each line."""
    @property
    def K(self) -> _F64Array:
        """(N, 3, 2) gain P H^T S^-1 applied for each line; zeros for a refused line."""

@final
class BatchResult:
    """What Filter.run returns: one row per step, after the step's last update."""

    @property
    def states(self) -> _F64Array:
        """(N, 3) states [x, y, theta]."""
    @property
    def covariances(self) -> _F64Array:
        """(N, 3, 3) covariances."""
    @property
    def compass_nis(self) -> _F64Array:
        """(N,) compass NIS, NaN at steps without a heading."""
    @property
    def compass_accepted(self) -> _BoolArray:
        """(N,) whether the step's heading was fused (False without one)."""
    @property
    def line_nis(self) -> _F64Array:
        """(N, K) line NIS, NaN for unused slots."""
    @property
    def line_accepted(self) -> _BoolArray:
        """(N, K) whether each line was fused (False for unused slots)."""

@final
class Filter:
    """The extended Kalman filter of a differential-drive robot (Hoang et al., with the
    paper's errata fixed): prediction from wheel speeds (eqs. 1-9) or odometry deltas,
    compass and laser-line updates in Joseph form with chi-square gates.

    ``pose`` (x, y, theta) defaults to the origin, ``covariance`` (3x3, symmetric positive
    definite) to 1e-4 I. ``config`` is a dict of the Localizer's config groups, of which
    the filter uses ``robot`` (wheel_radius, track in m; default 0.05, 0.60),
    ``wheel_noise`` (delta, floor in (rad/s)^2; default 0.01, 1.296e-3), ``odometry_noise``
    (a1, b1, a2, b2, a3, a4, b3), ``laser_mount`` (x, y, theta on the robot; default the
    origin), ``compass`` (variance in rad^2, default (2 deg)^2; gate_probability, default
    0.999) and ``matching.gate_probability`` (the line gate, default 0.99, 2 dof ->
    NIS <= 9.21); ``compass.recover_after`` is the Localizer's, the bare filter has no
    lock-out recovery. ``gating=False`` fuses every measurement.
    """

    def __new__(
        cls,
        pose: Optional[_Pose] = None,
        covariance: Optional[_ArrayLike] = None,
        config: Optional[_ConfigDict] = None,
        *,
        gating: bool = True,
    ) -> Filter: ...
    @property
    def state(self) -> _F64Array:
        """(3,) state [x, y, theta] (m, m, rad), a new array each time. Assign three
        finite numbers to replace it (theta wrapped; the covariance kept), as FilterPy's
        ``x``."""
    @state.setter
    def state(self, value: _Pose) -> None: ...
    @property
    def covariance(self) -> _F64Array:
        """(3, 3) covariance of (x, y, theta), a new array each time. Assign a 3x3 matrix
        to replace it (the state kept), as FilterPy's ``P``: finite, symmetric to a
        relative tolerance of 1.5e-8 (then symmetrised) and positive definite."""
    @covariance.setter
    def covariance(self, value: _ArrayLike) -> None: ...
    @property
    def laser_mount(self) -> Tuple[float, float, float]:
        """The laser's pose on the robot (x, y, theta)."""
    @property
    def counts(self) -> dict[str, int]:
        """Counts so far: predictions, compass_accepted, compass_rejected,
        lines_accepted, lines_rejected."""
    def reset(self, pose: _Pose, covariance: _ArrayLike) -> None:
        """Replaces the state and covariance."""
    def predict_wheels(self, left: float, right: float, dt: float) -> None:
        """Prediction from wheel speeds ``left``, ``right`` (rad/s, positive forward) held
        for ``dt`` seconds (> 0): x- = f(x, u), P- = A P A^T + W Q W^T."""
    def predict_odometry(self, ds: float, dtheta: float) -> None:
        """Prediction from an odometry delta: ``ds`` (m) along the mid-angle heading,
        ``dtheta`` (rad), with the odometry noise model."""
    def update_compass(self, heading: float, variance: Optional[float] = None) -> UpdateOutcome:
        """Fuses a compass heading (rad, map frame) with ``variance`` (rad^2; default the
        config's); the innovation is wrapped. The outcome has ``y``, ``S`` and ``K``."""
    def update_lines(
        self, observed: _ArrayLike, covariances: _ArrayLike, map_lines: _ArrayLike
    ) -> LineUpdates:
        """Fuses N matched laser lines one at a time, in order: ``observed`` (N, 2) as
        (r, psi) in the laser frame (m, rad), ``covariances`` (N, 2, 2) of (r, psi),
        ``map_lines`` (N, 2) as (rho, beta) in the world frame. The result has each
        line's ``nis``, ``accepted``, ``y``, ``S`` and ``K``. All or nothing: on an error
        the filter is left as it was."""
    def run(
        self,
        *,
        wheels: Optional[_ArrayLike] = None,
        odometry: Optional[_ArrayLike] = None,
        compass: Optional[_ArrayLike] = None,
        compass_mask: Optional[_BoolArray] = None,
        line_observed: Optional[_ArrayLike] = None,
        line_covariances: Optional[_ArrayLike] = None,
        line_map: Optional[_ArrayLike] = None,
        line_counts: Optional[_ArrayLike] = None,
    ) -> BatchResult:
        """Runs N steps in one native call (the GIL released): each step predicts from
        ``wheels`` (N, 3) as (left, right, dt) or ``odometry`` (N, 2) as (ds, dtheta),
        then fuses ``compass`` (N,) headings where ``compass_mask`` (N,) is True (all
        steps without a mask), then the first ``line_counts[k]`` (default K) of the lines
        ``line_observed`` (N, K, 2), ``line_covariances`` (N, K, 2, 2), ``line_map``
        (N, K, 2). Unused entries are never read (they may be NaN). Exactly the results of
        the per-call methods. All or nothing: an error names the step and leaves the
        filter as it was."""
    def __copy__(self) -> Filter:
        """An independent copy (a Filter shares nothing mutable, so as ``__deepcopy__``)."""
    def __deepcopy__(self, memo: dict[int, Any]) -> Filter:
        """An independent copy: it continues bit for bit as the original would."""
    def __getstate__(self) -> dict[str, Any]:
        """Everything the filter holds as a dict of numbers (version 1; floats exact)."""
    def __setstate__(self, state: Mapping[str, Any]) -> None:
        """Replaces everything with a dict from ``__getstate__`` (validated)."""
    def __reduce__(self) -> Tuple[type[Filter], Tuple[()], dict[str, Any]]:
        """For pickle: rebuilt with ``Filter()`` and ``__setstate__``."""

@final
class Lines:
    """Lines observed in one scan, in the sensor frame: x cos(psi) + y sin(psi) = r with
    r >= 0, their (r, psi) covariances and segment end points."""

    def __new__(
        cls,
        lines: _ArrayLike,
        covariances: _ArrayLike,
        starts: _ArrayLike,
        ends: _ArrayLike,
        num_points: Optional[_ArrayLike] = None,
    ) -> Lines: ...
    @property
    def lines(self) -> _F64Array:
        """(N, 2) (r, psi): distance (m) and normal direction (rad)."""
    @property
    def covariances(self) -> _F64Array:
        """(N, 2, 2) covariances of (r, psi) (m^2, m rad, rad^2)."""
    @property
    def starts(self) -> _F64Array:
        """(N, 2) first end points (m), in scan order."""
    @property
    def ends(self) -> _F64Array:
        """(N, 2) last end points (m), in scan order."""
    @property
    def lengths(self) -> _F64Array:
        """(N,) segment lengths (m)."""
    @property
    def num_points(self) -> _U64Array:
        """(N,) scan points each line was fitted to."""
    def __len__(self) -> int: ...

def extract_lines(
    ranges: _ArrayLike,
    angle_min: float,
    angle_increment: float,
    range_min: float = 0.0,
    range_max: float = ...,
    params: Optional[_ConfigDict] = None,
) -> Lines:
    """Extracts the lines of one laser scan (split-and-merge, weighted least-squares fits
    with the inverse Fisher information as covariance, chi-square merging). Beam i has
    bearing angle_min + i * angle_increment (rad, counter-clockwise, sensor frame);
    readings NaN, infinite, <= range_min or >= range_max (default inf: no limit) are "no
    return" and skipped. ``params``: the [localizer.extraction] keys of ``ekf config``."""

@final
class LineMap:
    """A map of walls: line segments in one world frame (docs/map-format.md)."""

    def __new__(cls, segments: _ArrayLike, frame_id: str = "map") -> LineMap:
        """From (N, 2, 2) end points [[x0, y0], [x1, y1]] (m)."""
    @staticmethod
    def load(path: _PathLike) -> "LineMap":
        """Reads a JSON map file (OSError if unreadable, ValueError if invalid)."""
    @staticmethod
    def from_json(text: str) -> "LineMap": ...
    def to_json(self) -> str: ...
    def save(self, path: _PathLike) -> None: ...
    @staticmethod
    def from_scan(lines: Lines, sensor_pose: _Pose) -> "LineMap":
        """The paper's global map: one scan's lines as walls, placed with the sensor pose
        (robot pose (+) laser mount)."""
    @staticmethod
    def build_from_log(
        path: _PathLike,
        config: Union[None, _PathLike, _ConfigDict] = None,
        *,
        from_truth: bool = True,
        init_from_truth: bool = False,
        params: Optional[_ConfigDict] = None,
    ) -> Tuple["LineMap", dict[str, Any]]:
        """``ekf map build`` on a ROS 2 bag; returns the map and the --json summary."""
    @staticmethod
    def build_slam(
        path: _PathLike,
        config: Union[None, _PathLike, _ConfigDict] = None,
    ) -> Tuple["LineMap", _F64Array, dict[str, Any]]:
        """``ekf map build --slam`` on a ROS 2 bag (no reference read); returns the map,
        the (N, 4) corrected pose at every scan ``[t (s), x, y, theta]`` and the --json
        summary."""
    @staticmethod
    def import_grid(
        yaml: _PathLike,
        config: Union[None, _PathLike, _ConfigDict] = None,
        params: Optional[_ConfigDict] = None,
    ) -> Tuple["LineMap", dict[str, Any]]:
        """``ekf map import-grid`` on a map_server / Nav2 YAML + PGM/PNG; returns the map
        and the --json summary. ``params``: scan_spacing, beams, max_range,
        min_sightings."""
    @property
    def segments(self) -> _F64Array:
        """(N, 2, 2) wall end points (m)."""
    @property
    def lines(self) -> _F64Array:
        """(N, 2) (rho, beta) of the walls: x cos(beta) + y sin(beta) = rho."""
    @property
    def frame_id(self) -> str: ...
    def __len__(self) -> int: ...

@final
class MapBuilder:
    """Fuses the lines of many scans taken at known sensor poses into a map."""

    def __new__(cls, params: Optional[_ConfigDict] = None) -> MapBuilder:
        """``params``: gate_probability, tolerance_rho (m), tolerance_beta (rad),
        max_gap (m), min_sightings."""
    def add_scan(self, lines: Lines, sensor_pose: _Pose) -> None: ...
    def finish(self) -> LineMap:
        """The map so far; the builder can take more scans afterwards."""
    def __len__(self) -> int: ...

@final
class Matches:
    """The association of one scan's lines with a map (M matches, by increasing NIS)."""

    @property
    def observed(self) -> _U64Array:
        """(M,) index of the observed line."""
    @property
    def map(self) -> _U64Array:
        """(M,) index of the map wall."""
    @property
    def nis(self) -> _F64Array:
        """(M,) NIS of each pair."""
    @property
    def innovations(self) -> _F64Array:
        """(M, 2) innovation (r, psi), psi wrapped."""
    @property
    def noise(self) -> _F64Array:
        """(M, 2, 2) measurement noise to fuse with (observed plus map)."""
    @property
    def overlap(self) -> _F64Array:
        """(M,) overlap of the observed segment with its wall (m)."""
    @property
    def rejected(self) -> list[Tuple[int, str]]:
        """Unmatched observed lines as (index, reason)."""
    def __len__(self) -> int: ...

def match_lines(
    lines: Lines,
    line_map: LineMap,
    pose: _Pose,
    covariance: _ArrayLike,
    laser_mount: Optional[_Pose] = None,
    params: Optional[_ConfigDict] = None,
) -> Matches:
    """Associates observed lines with map walls at the state (pose, 3x3 covariance):
    chi-square gate (2 dof) on the line innovation, segment overlap, each wall at most
    once, conflicts resolved by increasing NIS. ``params``: [localizer.matching] keys."""

@final
class Localizer:
    """One localization step: prediction, compass, and scans (extract -> match ->
    sequential update). Without ``line_map`` the first scan becomes the map."""

    def __new__(
        cls,
        pose: _Pose,
        covariance: _ArrayLike,
        line_map: Optional[LineMap] = None,
        config: Optional[_ConfigDict] = None,
    ) -> Localizer: ...
    def predict_wheels(self, left: float, right: float, dt: float) -> None: ...
    def predict_odometry(self, ds: float, dtheta: float) -> None: ...
    def update_compass(self, heading: float, variance: Optional[float] = None) -> CompassUpdate: ...
    def update_scan(
        self,
        ranges: _ArrayLike,
        angle_min: float,
        angle_increment: float,
        range_min: float = 0.0,
        range_max: float = ...,
    ) -> dict[str, Union[int, bool]]:
        """Counts: extracted, matched, rejected, fused, refused, merged, refitted, map_built."""
    @property
    def state(self) -> _F64Array: ...
    @property
    def covariance(self) -> _F64Array: ...
    @property
    def sensor_pose(self) -> Tuple[float, float, float]: ...
    @property
    def line_map(self) -> LineMap: ...
    @property
    def last_lines(self) -> Lines: ...
    @property
    def last_fusions(self) -> list[Tuple[int, int, float, bool]]:
        """(observed index, map index, nis, accepted) per match, in fusion order."""

@final
class TimedLocalizer:
    """Stamped inputs (ns) pushed as they arrive, fused in stamp order: each is held until
    one stamped ``max_lag`` (s) later has come, so one that comes up to ``max_lag`` late
    is fused at its own stamp; later ones are dropped and counted (``add_*`` returns
    False). With ``line_map`` a lost filter is found again by searching the map."""

    def __new__(
        cls,
        pose: _Pose,
        covariance: _ArrayLike,
        line_map: Optional[LineMap] = None,
        config: Optional[_ConfigDict] = None,
        mode: _ReplayMode = "laser+compass",
        max_lag: float = 0.5,
        start_ns: int = 0,
        global_localization: bool = False,
    ) -> TimedLocalizer: ...
    def add_wheel_angles(self, t_ns: int, left: float, right: float) -> bool: ...
    def add_wheel_speeds(self, t_ns: int, left: float, right: float) -> bool: ...
    def add_odometry(self, t_ns: int, pose: _Pose) -> bool: ...
    def add_heading(self, t_ns: int, heading: float, variance: Optional[float] = None) -> bool: ...
    def add_position(self, t_ns: int, xy: _ArrayLike, covariance: _ArrayLike) -> bool: ...
    def add_scan(
        self,
        t_ns: int,
        ranges: _ArrayLike,
        angle_min: float,
        angle_increment: float,
        range_min: float = 0.0,
        range_max: float = ...,
    ) -> bool: ...
    def flush(self) -> None:
        """Fuses every input still held (when the inputs have ended)."""
    def pose_now(self) -> Optional[Tuple[int, _F64Array, _F64Array]]:
        """(t_ns, state (3,), covariance (3, 3)) predicted through the held motion."""
    @property
    def state(self) -> _F64Array: ...
    @property
    def covariance(self) -> _F64Array: ...
    @property
    def t_ns(self) -> Optional[int]: ...
    @property
    def held(self) -> int: ...
    @property
    def line_map(self) -> LineMap: ...
    def counts(self) -> dict[str, Any]: ...
    def take_trajectory(self) -> Tuple[_U64Array, _F64Array, _F64Array]:
        """(t_ns (N,), states (N, 3), covariances (N, 3, 3)) since the last call."""

@final
class ReplayResult:
    """The estimate at every motion step and scan (the rows of ``ekf replay --tum``), the
    log's reference poses, and the summary of ``ekf replay --json``."""

    @property
    def t(self) -> _F64Array:
        """(N,) log times (s)."""
    @property
    def t_ns(self) -> _U64Array:
        """(N,) log times (ns), exact."""
    @property
    def x(self) -> _F64Array: ...
    @property
    def y(self) -> _F64Array: ...
    @property
    def theta(self) -> _F64Array: ...
    @property
    def covariance(self) -> _F64Array:
        """(N, 3, 3)."""
    @property
    def reference_t(self) -> _F64Array: ...
    @property
    def reference_x(self) -> _F64Array: ...
    @property
    def reference_y(self) -> _F64Array: ...
    @property
    def reference_theta(self) -> _F64Array: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def map(self) -> LineMap:
        """The map at the end (the grown map with ``grow_map``)."""

def replay(
    path: _PathLike,
    config: Union[None, _PathLike, _ConfigDict] = None,
    mode: _ReplayMode = "laser+compass",
    map: Optional[_PathLike] = None,
    init_from_truth: bool = False,
    global_localization: bool = False,
    grow_map: bool = False,
) -> ReplayResult:
    """``ekf replay`` on a ROS 2 bag (same code), writing no files. ``mode``: odometry,
    compass, laser or laser+compass. ``map``: JSON line map (None: the first scan).
    ``global_localization``: no initial pose, the map is searched from the first scans
    (``ekf replay --global``; needs ``map``); ``summary["tracking"]["locked_on_scan"]``
    says when it locked on. ``grow_map``: keep adding walls to the first-scan map
    (``ekf replay --grow-map``); ``map`` of the result is the grown map."""

@final
class SimulationResult:
    """A simulated run: the true pose at every 0.1 s step, the in-loop estimate and its
    NEES when the robot steered by an estimator (empty arrays otherwise), the distance of
    the true position from the commanded path, and the summary of ``ekf simulate --json``."""

    @property
    def t(self) -> _F64Array:
        """(N,) time since the start (s)."""
    @property
    def x(self) -> _F64Array:
        """(N,) true x (m)."""
    @property
    def y(self) -> _F64Array:
        """(N,) true y (m)."""
    @property
    def theta(self) -> _F64Array:
        """(N,) true heading (rad)."""
    @property
    def estimate_x(self) -> _F64Array: ...
    @property
    def estimate_y(self) -> _F64Array: ...
    @property
    def estimate_theta(self) -> _F64Array: ...
    @property
    def nees(self) -> _F64Array:
        """(N,) the estimate's NEES against the truth (3 dof)."""
    @property
    def nees_position(self) -> _F64Array:
        """(N,) the NEES of its position alone, with P's position block (2 dof)."""
    @property
    def nees_heading(self) -> _F64Array:
        """(N,) the NEES of its heading alone (1 dof)."""
    @property
    def path_deviation(self) -> _F64Array:
        """(N,) distance of the true position from the commanded path (m)."""
    @property
    def summary(self) -> dict[str, Any]: ...

def simulate(
    scenario: str,
    out: Optional[_PathLike] = None,
    seed: int = 1,
    duration: Optional[float] = None,
    steer_by: _SteerBy = "truth",
    resolution: Optional[float] = None,
    slips_per_minute: Optional[float] = None,
    compass_bias_deg: Optional[float] = None,
    compass_outliers: Optional[float] = None,
) -> SimulationResult:
    """``ekf simulate`` (same code): ``scenario`` is paper, triangle, walls, l-room,
    corridor or a JSON line map; ``out`` also writes the ROS 2 bag; ``steer_by`` is
    truth, ekf or odometry. Same seed, same run."""
