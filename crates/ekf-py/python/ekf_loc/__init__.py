"""EKF localization for differential-drive robots: wheel odometry, a compass and straight
lines from a 2-D laser scanner, after Hoang et al., "Development of an EKF-based
Localization Algorithm Using Compass Sensor and LRF" (with the paper's errata fixed).

Conventions (ROS REP-103): SI units and radians everywhere; world x east, y north; robot
x forward, y left; headings counter-clockwise from the world x axis, wrapped to
(-pi, pi]. A pose is ``(x, y, theta)``; covariances are 3x3 in that order. A line is
``x cos(beta) + y sin(beta) = rho`` with ``rho >= 0`` (world frame), or ``(r, psi)`` in the
same form in the laser's frame. Arrays are float64 numpy arrays.

Invalid input raises ``ValueError`` (or ``TypeError`` for a wrong kind of argument) with a
message naming the argument; files that cannot be read or written raise ``OSError``.
"""

from ._ekf_loc import (
    BatchResult,
    CompassUpdate,
    Filter,
    LineMap,
    LineUpdates,
    Lines,
    Localizer,
    MapBuilder,
    Matches,
    ReplayResult,
    SimulationResult,
    TimedLocalizer,
    UpdateOutcome,
    __version__,
    extract_lines,
    match_lines,
    replay,
    simulate,
)

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
