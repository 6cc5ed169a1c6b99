//! Scenarios: a room, a path through it, the robot and its sensors, and how long to drive.

use super::path::{Path, PathError};
use super::robot::RobotModel;
use super::room::Room;
use super::sensors::{CompassModel, LaserModel};
use ekf_core::Pose2;
use lrf_lines::LineMap;
use nalgebra::Point2;
use serde::Serialize;

/// Largest extent of a user's room (m): the path is a dense polyline, so a map in the
/// wrong unit would make it huge.
const MAX_ROOM: f64 = 1000.0;

/// The built-in scenarios, by name.
pub const BUILTIN: [&str; 6] = [
    "paper",
    "triangle",
    "walls",
    "l-room",
    "corridor",
    "two-rooms",
];

/// Everything a simulation run needs except the seed.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Its name (a built-in's, or the map file's).
    pub name: String,
    /// The walls.
    pub room: Room,
    /// The closed path the robot follows.
    pub path: Path,
    /// Where the robot starts (by default the path's start, facing along it); the
    /// follower joins the path at its nearest point.
    pub start: Pose2<f64>,
    /// The robot.
    pub robot: RobotModel,
    /// The compass.
    pub compass: CompassModel,
    /// The laser scanner.
    pub laser: LaserModel,
    /// How the robot drives.
    pub drive: Drive,
    /// Filter and control period `Δt` (s). The paper: 0.1.
    pub dt: f64,
    /// How long to drive (s).
    pub duration_s: f64,
}

/// The path follower's settings (pure pursuit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Drive {
    /// Forward speed (m/s).
    pub speed: f64,
    /// Look-ahead distance (m).
    pub lookahead: f64,
    /// Largest turn rate (rad/s).
    pub max_turn_rate: f64,
}

impl Default for Drive {
    /// 0.3 m/s, 0.5 m look-ahead, 1 rad/s.
    fn default() -> Self {
        Self {
            speed: 0.3,
            lookahead: 0.5,
            max_turn_rate: 1.0,
        }
    }
}

/// Why a scenario could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// Not a built-in name.
    #[error("unknown scenario {name:?}; the built-in ones are {}, or give a line map (.json)", BUILTIN.join(", "))]
    Unknown {
        /// The name given.
        name: String,
    },
    /// The map has no walls, or is too small for a path 1 m inside it.
    #[error("{name}: the map's walls span {width:.2} m × {height:.2} m; a path 1 m inside them needs at least 3 m × 3 m")]
    MapTooSmall {
        /// The map.
        name: String,
        /// Width of the walls' bounding box (m).
        width: f64,
        /// Height of the walls' bounding box (m).
        height: f64,
    },
    /// The map is larger than a room the simulator drives round (a map in millimetres?).
    #[error("{name}: the map's walls span {width:.0} m × {height:.0} m; the simulator takes rooms up to 1000 m across (are the coordinates in metres?)")]
    MapTooLarge {
        /// The map.
        name: String,
        /// Width of the walls' bounding box (m).
        width: f64,
        /// Height of the walls' bounding box (m).
        height: f64,
    },
    /// The path could not be built.
    #[error("{0}")]
    Path(#[from] PathError),
}

fn points(corners: &[[f64; 2]]) -> Vec<Point2<f64>> {
    corners.iter().map(|c| Point2::new(c[0], c[1])).collect()
}

impl Scenario {
    fn new(name: &str, room: Room, path: Path) -> Self {
        Self {
            name: name.into(),
            room,
            start: path.start_pose(),
            path,
            robot: RobotModel::default(),
            compass: CompassModel::default(),
            laser: LaserModel::default(),
            drive: Drive::default(),
            dt: 0.1,
            duration_s: 120.0,
        }
    }

    /// A built-in scenario:
    /// - `paper`: the paper's 6 m × 4 m room, a rounded rectangle 1 m inside the walls
    ///   (corner radius 0.5 m; Fig. 9–11a);
    /// - `triangle`: the same room, a rounded triangle (Fig. 11b);
    /// - `walls`: the same room, a loop 0.6 m from the walls (Fig. 12);
    /// - `l-room`: an L-shaped room with three pillars, a loop through both arms;
    /// - `corridor`: a 20 m × 2.2 m corridor, a long loop down and back;
    /// - `two-rooms`: two 6 m × 4 m rooms joined by an 8 m corridor
    ///   ([`Room::two_rooms`]), a loop from room A through the corridor into room B and
    ///   back (lanes 0.6 m from the corridor's walls), 300 s: most of it out of the first
    ///   scan's room.
    ///
    /// Each starts on its path's first straight edge, heading along it.
    /// The three scenarios in the paper's room use the paper's compass (σ = 0.1°,
    /// [`CompassModel::paper`]); the others a CMPS03 as measured (σ = 2°).
    pub fn builtin(name: &str) -> Result<Self, ScenarioError> {
        let (room, corners, radius, start) = match name {
            "paper" => (
                Room::paper(),
                points(&[[1.0, 1.0], [5.0, 1.0], [5.0, 3.0], [1.0, 3.0]]),
                0.5,
                [2.0, 1.0],
            ),
            "triangle" => (
                Room::paper(),
                points(&[[1.0, 0.9], [5.0, 0.9], [3.0, 3.2]]),
                0.4,
                [2.0, 0.9],
            ),
            "walls" => (
                Room::paper(),
                points(&[[0.6, 0.6], [5.4, 0.6], [5.4, 3.4], [0.6, 3.4]]),
                0.4,
                [1.5, 0.6],
            ),
            "l-room" => (
                Room::l_shaped(),
                points(&[
                    [1.2, 1.2],
                    [8.8, 1.2],
                    [8.8, 2.8],
                    [3.8, 2.8],
                    [3.8, 6.8],
                    [1.2, 6.8],
                ]),
                0.5,
                [2.5, 1.2],
            ),
            "corridor" => (
                Room::corridor(),
                points(&[[1.0, 0.6], [19.0, 0.6], [19.0, 1.6], [1.0, 1.6]]),
                0.45,
                [3.0, 0.6],
            ),
            "two-rooms" => (
                Room::two_rooms(),
                points(&[[1.0, 1.6], [19.0, 1.6], [19.0, 2.4], [1.0, 2.4]]),
                0.35,
                [2.0, 1.6],
            ),
            _ => return Err(ScenarioError::Unknown { name: name.into() }),
        };
        let path = Path::rounded_polygon(&corners, radius)?;
        let mut scenario = Self::new(name, room, path);
        // On the first straight edge, facing along it (east): the first scan, which
        // becomes the map, looks into the room rather than into a corner.
        scenario.start = Pose2::new(start[0], start[1], 0.0);
        if scenario.room == Room::paper() {
            scenario.compass = CompassModel::paper();
        }
        if name == "two-rooms" {
            scenario.duration_s = 300.0;
        }
        Ok(scenario)
    }

    /// A user's room from a line map: the robot drives a rounded rectangle (corner radius
    /// 0.5 m) 1 m inside the bounding box of the walls. Suits convex rooms; walls inside
    /// the loop are the user's to avoid.
    pub fn from_map(name: &str, map: &LineMap) -> Result<Self, ScenarioError> {
        let room = Room::from_map(map);
        let too_small = |w: f64, h: f64| ScenarioError::MapTooSmall {
            name: name.into(),
            width: w,
            height: h,
        };
        let (lo, hi) = room.bounds().ok_or_else(|| too_small(0.0, 0.0))?;
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        if w < 3.0 || h < 3.0 {
            return Err(too_small(w, h));
        }
        if w > MAX_ROOM || h > MAX_ROOM {
            return Err(ScenarioError::MapTooLarge {
                name: name.into(),
                width: w,
                height: h,
            });
        }
        let corners = points(&[
            [lo.x + 1.0, lo.y + 1.0],
            [hi.x - 1.0, lo.y + 1.0],
            [hi.x - 1.0, hi.y - 1.0],
            [lo.x + 1.0, hi.y - 1.0],
        ]);
        let path = Path::rounded_polygon(&corners, 0.5)?;
        Ok(Self::new(name, room, path))
    }

    /// Number of control steps in [`duration_s`](Self::duration_s).
    pub fn steps(&self) -> u64 {
        (self.duration_s / self.dt).round().max(0.0) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_robot_preset_starts_where_the_paper_scenario_does() {
        let c = ekf_ros::config::Config::preset("paper-robot").unwrap();
        let start = Scenario::builtin("paper").unwrap().start;
        let i = &c.initial;
        assert_eq!((i.x, i.y, i.theta), (start.x, start.y, start.theta));
    }

    #[test]
    fn every_builtin_path_keeps_clear_of_the_walls() {
        for name in BUILTIN {
            let s = Scenario::builtin(name).unwrap();
            let closest = s
                .path
                .points()
                .iter()
                .map(|p| s.room.clearance(p))
                .fold(f64::INFINITY, f64::min);
            assert!(closest >= 0.5, "{name}: {closest}");
        }
        assert!(matches!(
            Scenario::builtin("moon"),
            Err(ScenarioError::Unknown { .. })
        ));
    }

    #[test]
    fn a_map_gives_a_loop_inside_it() {
        let s = Scenario::from_map("m.json", &Room::paper().to_map()).unwrap();
        // A 4 m × 2 m loop: straight edges 2·3 + 2·1 m and four quarter circles of 0.5 m.
        assert!((s.path.length() - (8.0 + std::f64::consts::PI)).abs() < 0.01);
        let small = Room::polygon(&[[0.0, 0.0], [2.0, 0.0], [2.0, 5.0]], &[], 0.0);
        assert!(matches!(
            Scenario::from_map("s.json", &small.to_map()),
            Err(ScenarioError::MapTooSmall { .. })
        ));
        assert_eq!(Scenario::builtin("paper").unwrap().steps(), 1200);
        let huge = Room::polygon(&[[0.0, 0.0], [6000.0, 0.0], [6000.0, 4000.0]], &[], 0.0);
        assert!(matches!(
            Scenario::from_map("mm.json", &huge.to_map()),
            Err(ScenarioError::MapTooLarge { .. })
        ));
    }
}
