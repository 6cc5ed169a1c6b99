//! The `ekf` command line: every subcommand and its arguments, as clap parses them.
//! The doc comments are the `--help` text.

use clap::{Args, Parser, Subcommand, ValueEnum};
use ekf_cli::commands::grid::GridImportParams;
use std::path::PathBuf;

/// EKF localization with wheel odometry, a compass and 2-D laser line features.
#[derive(Debug, Parser)]
#[command(name = "ekf", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the filter over a ROS 2 bag (MCAP or sqlite3): a trajectory (TUM), an MCAP for Foxglove
    /// and ROS 2 tools, and a summary (with accuracy when the log has a reference).
    Replay(ReplayArgs),
    /// The paper's Fig. 9/10: replay a bag in all four modes (odometry, compass, laser,
    /// laser+compass) and compare each estimate with the log's reference trajectory.
    Compare(CompareArgs),
    /// The paper's experiments in simulation: an SVG figure and a JSON table each.
    Experiment(ExperimentArgs),
    /// Print the documented default configuration (TOML), or a preset's overrides.
    Config(ConfigArgs),
    /// Simulate the paper's robot in a room and write a ROS 2 bag with exact ground truth
    /// (/joint_states, /compass, /scan, /tf_static, /ground_truth).
    Simulate(SimulateArgs),
    /// Run the filter on the robot's serial devices (SICK LMS 2xx, MODBUS base
    /// controller, NMEA GPS), print poses, and record everything for `ekf replay`.
    Live(LiveArgs),
    /// Emulate the robot's devices on pseudo-terminals, driven in real time by the
    /// simulator, for `ekf live` to run against; prints the device paths.
    Emulate(EmulateArgs),
    /// Line maps.
    Map {
        #[command(subcommand)]
        action: MapAction,
    },
    /// Convert a CARMEN or MRPT text log into a ROS 2 bag (MCAP) with /odom, /scan,
    /// /tf_static, /ground_truth (corrected CARMEN logs) and optionally a synthetic /compass.
    Import {
        #[command(subcommand)]
        format: ImportFormat,
    },
    /// The real-log benchmark: import each CARMEN log (a file, or every *.log / *.log.gz
    /// in a folder), build its map from the reference, replay it laser-only from the first
    /// reference pose, and print one row per log.
    Corpus(CorpusArgs),
    /// Absolute and relative pose errors of a trajectory against a reference, as `evo`
    /// computes them (same frame, no alignment unless --align).
    Evaluate(EvaluateArgs),
}

#[derive(Debug, Subcommand)]
pub enum ImportFormat {
    /// A CARMEN log (ODOM, FLASER, ROBOTLASER1), plain or "corrected"; .gz is read directly.
    Carmen(ImportCarmenArgs),
    /// MRPT's text export (ODOM, RAWSCAN).
    Mrpt(ImportMrptArgs),
}

#[derive(Debug, Subcommand)]
pub enum MapAction {
    /// Build a line map (JSON) from a bag: from its first scan (the paper's global map),
    /// or with --from-truth from every scan placed along the log's reference trajectory.
    Build(MapBuildArgs),
    /// Extract the walls of a ROS occupancy-grid map (map_server / Nav2 YAML with a PGM or
    /// PNG image) as a line map, by casting virtual laser scans through its free space.
    ImportGrid(MapImportGridArgs),
    /// Draw a line map as a ROS occupancy-grid map: a Nav2 YAML and a trinary PGM beside it
    /// (walls occupied, the rest of the bounding box free).
    ExportGrid(MapExportGridArgs),
    /// Compare a line map with a reference map: the share of the reference's wall length
    /// matched within 0.1 m and 2°, and the map's wall length with no counterpart.
    Compare(MapCompareArgs),
    /// Draw a line map to scale as SVG, with trajectories (TUM) over it.
    Plot(MapPlotArgs),
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Figure {
    Fig9,
    Fig11,
    Fig12,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CliSteering {
    /// The true pose.
    Truth,
    /// The laser + compass EKF in the loop.
    Ekf,
    /// Dead reckoning.
    Odometry,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CliMode {
    Odometry,
    Compass,
    Laser,
    #[value(name = "laser+compass")]
    LaserCompass,
}

/// What the filter of `ekf replay`, `ekf compare` and `ekf live` is set up from.
#[derive(Debug, Args)]
pub struct FilterInputs {
    /// Configuration file (TOML); `ekf config` prints the defaults.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Line map (JSON). Without it the map is built from the first scan, as in the paper.
    #[arg(long)]
    pub map: Option<PathBuf>,
}

/// The arguments of `ekf replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The ROS 2 bag: an .mcap or .db3 file, or a bag directory as `ros2 bag record`
    /// writes it.
    pub log: PathBuf,
    /// The configuration and the map.
    #[command(flatten)]
    pub inputs: FilterInputs,
    /// Which sensors the filter uses (the paper's four configurations).
    #[arg(long, value_enum, default_value_t = CliMode::LaserCompass)]
    pub mode: CliMode,
    /// Start at the log's first reference pose instead of the configured initial pose.
    #[arg(long)]
    pub init_from_truth: bool,
    /// Global localization: no initial pose; search the map (--map) from the first
    /// scans and start where the search locks on (the summary says at which scan).
    #[arg(long, conflicts_with = "init_from_truth", requires = "map")]
    pub global: bool,
    /// Write the estimate, lines, map and diagnostics to this MCAP bag (a path ending
    /// in `/`: a bag directory with metadata.yaml, as `ros2 bag record` writes).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the trajectory as TUM text (what evo reads).
    #[arg(long)]
    pub tum: Option<PathBuf>,
    /// Draw the trajectory over the map with the reference, the error over time and
    /// markers where lines were refused, the compass rejected, the filter lost or
    /// relocalized, as one SVG.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Keep adding walls to the first-scan map as the robot explores: every key scan
    /// (key_distance, key_angle of the slam table) adds its lines at the filter's pose, so the
    /// filter keeps localizing after it leaves the first room.
    #[arg(long, conflicts_with_all = ["map", "global"])]
    pub grow_map: bool,
    /// Write the map at the end (the grown map with --grow-map) as JSON.
    #[arg(long)]
    pub write_map: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The ROS 2 bag (.mcap, .db3 or a bag directory); it needs a reference trajectory (topics.ground_truth).
    pub log: PathBuf,
    /// The configuration and the map.
    #[command(flatten)]
    pub inputs: FilterInputs,
    /// Start at the log's first reference pose instead of the configured initial pose.
    #[arg(long)]
    pub init_from_truth: bool,
    /// Write one SVG with the trajectories (Fig. 9) and the position, x and y errors
    /// over time (Fig. 10).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf experiment`.
#[derive(Debug, Args)]
pub struct ExperimentArgs {
    /// fig9 (Fig. 9/10 over seeds, with NEES), fig11 (path following with and
    /// without the EKF), fig12 (driving round the first-scan map's walls).
    #[arg(value_enum)]
    pub figure: Figure,
    /// Where the figure, the table and logs go.
    #[arg(long, default_value = "out/experiments")]
    pub out_dir: PathBuf,
    /// The first seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Seeds to run (fig9; the figures show the first).
    #[arg(long, default_value_t = 20)]
    pub seeds: u32,
    /// Simulated time per run (s); default: the scenario's (120 s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Print the table as JSON (it is also written to OUT_DIR).
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf config`.
#[derive(Debug, Args)]
pub struct ConfigArgs {
    /// A built-in preset instead of the defaults (paper-robot: the simulated robot).
    #[arg(long)]
    pub preset: Option<String>,
}

/// The arguments of `ekf simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// A built-in scenario (paper, triangle, walls, l-room, corridor, two-rooms) or a line map
    /// (.json) whose room the robot drives around 1 m inside.
    pub scenario: String,
    /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
    /// with metadata.yaml.
    #[arg(long)]
    pub out: PathBuf,
    /// Noise seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Simulated time (s); default: the scenario's (120 s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// What steers the robot along its path.
    #[arg(long, value_enum, default_value_t = CliSteering::Truth)]
    pub steer_by: CliSteering,
    /// Laser angular resolution (degrees): 0.25, 0.5 or 1.
    #[arg(long)]
    pub resolution: Option<f64>,
    /// Wheel slip events per minute (default: none).
    #[arg(long)]
    pub slips_per_minute: Option<f64>,
    /// Compass bias (degrees; default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub compass_bias: Option<f64>,
    /// Probability of a compass outlier per reading (default 0.02).
    #[arg(long)]
    pub compass_outliers: Option<f64>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf live`.
#[derive(Debug, Args)]
pub struct LiveArgs {
    /// The laser's serial port.
    #[arg(long)]
    pub laser: String,
    /// The base controller's serial port (RS-485, MODBUS RTU).
    #[arg(long)]
    pub base: String,
    /// The GPS's serial port (NMEA).
    #[arg(long)]
    pub gps: Option<String>,
    /// The configuration and the map.
    #[command(flatten)]
    pub inputs: FilterInputs,
    /// Which sensors the filter uses.
    #[arg(long, value_enum, default_value_t = CliMode::LaserCompass)]
    pub mode: CliMode,
    /// Record the raw readings, /tf_static and the estimates to this MCAP bag (a path
    /// ending in `/`: a bag directory with metadata.yaml).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Print poses and the summary as JSON lines.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf emulate`.
#[derive(Debug, Args)]
pub struct EmulateArgs {
    /// A built-in scenario (paper, triangle, walls, l-room, corridor, two-rooms) or a line map
    /// (.json) whose room the robot drives around 1 m inside.
    #[arg(long, default_value = "paper")]
    pub scenario: String,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How long the robot drives (s), from when ekf live has connected; default: the
    /// scenario's (120 s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Write the true pose (/ground_truth, nav_msgs/Odometry) to this MCAP, stamped
    /// with the wall clock as ekf live stamps its recording.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Folder for the device links (laser, base, gps) and live.toml (which stays, for
    /// ekf replay of a recording); default: a new one in the temporary folder,
    /// removed at the end.
    #[arg(long)]
    pub dir: Option<PathBuf>,
    /// Where the room's origin lies (`LAT,LON[,ALT]`; x east, y north): the GPS reports
    /// fixes of the robot. Default: no fix, as indoors.
    #[arg(long, allow_hyphen_values = true)]
    pub gps_origin: Option<ekf_cli::geo::GeoOrigin>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf corpus`.
#[derive(Debug, Args)]
pub struct CorpusArgs {
    /// CARMEN logs, or folders of them.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Where the imported bags, maps and TUM trajectories go.
    #[arg(long, default_value = "out/corpus")]
    pub work_dir: PathBuf,
    /// Filter settings (TOML); default: the documented defaults.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Global localization: replay without an initial pose (ekf replay --global).
    #[arg(long)]
    pub global: bool,
    /// Print the rows as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf evaluate`.
#[derive(Debug, Args)]
pub struct EvaluateArgs {
    /// The estimated trajectory: a TUM file, or a ROS 2 bag (its /ekf/pose, else
    /// /ground_truth, unless --est-topic names one).
    pub estimate: PathBuf,
    /// The reference trajectory: a TUM file, or a ROS 2 bag (its /ground_truth unless
    /// --truth-topic names one).
    #[arg(long)]
    pub truth: PathBuf,
    /// Pose topic of a bag estimate.
    #[arg(long)]
    pub est_topic: Option<String>,
    /// Pose topic of a bag reference.
    #[arg(long, default_value = "/ground_truth")]
    pub truth_topic: String,
    /// Align the estimate to the reference first (rigid SE(2) Umeyama, as `evo -a`).
    #[arg(long)]
    pub align: bool,
    /// Draw both trajectories and the position and heading errors over time as one
    /// SVG (as `evo_ape --plot`).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf import carmen`.
#[derive(Debug, Args)]
pub struct ImportCarmenArgs {
    /// The CARMEN log.
    pub input: PathBuf,
    /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
    /// with metadata.yaml.
    #[arg(long)]
    pub out: PathBuf,
    /// Which flavour the log is: corrected (SLAM poses at the scans, odometry reset
    /// to them), plain, or auto (corrected if the resets are found).
    #[arg(long, value_enum, default_value_t = Flavour::Auto)]
    pub flavour: Flavour,
    /// Range limit of FLASER scans (m) unless the log's PARAM lines give one.
    #[arg(long, default_value_t = 50.0)]
    pub laser_max_range: f64,
    /// Also write a SYNTHETIC /compass: the reference heading plus Gaussian noise of
    /// this standard deviation (degrees). Labelled as synthetic in the bag's metadata.
    #[arg(long, value_name = "SIGMA")]
    pub synthetic_compass_deg: Option<f64>,
    /// Seed of the synthetic compass noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Refuse a log whose timestamps need repair (negative, zero, below a nanosecond,
    /// out of order, or a clock broken throughout) instead of repairing them.
    #[arg(long)]
    pub strict: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf import mrpt`.
#[derive(Debug, Args)]
pub struct ImportMrptArgs {
    /// The MRPT text log.
    pub input: PathBuf,
    /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
    /// with metadata.yaml.
    #[arg(long)]
    pub out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf map build`.
#[derive(Debug, Args)]
pub struct MapBuildArgs {
    /// The ROS 2 bag: an .mcap or .db3 file, or a bag directory as `ros2 bag record`
    /// writes it.
    pub log: PathBuf,
    /// The map file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Place every scan at the reference pose and fuse repeated sightings of a wall.
    #[arg(long, conflicts_with = "slam")]
    pub from_truth: bool,
    /// Build the map without a reference (SLAM): localize in the map as it grows, close
    /// loops where the robot comes back, optimise the key scans' pose graph, and fuse
    /// every key scan's lines at its corrected pose. The reference topic is not read.
    #[arg(long)]
    pub slam: bool,
    /// With --slam: write the corrected trajectory (a pose per scan) as TUM.
    #[arg(long, requires = "slam")]
    pub tum: Option<PathBuf>,
    /// With a first-scan map: place the scan at the first reference pose instead of
    /// the configured initial pose.
    #[arg(long, conflicts_with = "slam")]
    pub init_from_truth: bool,
    /// Configuration file (TOML): topics, laser mount, extraction parameters.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf map import-grid`.
#[derive(Debug, Args)]
pub struct MapImportGridArgs {
    /// The map's YAML file (`image`, `resolution`, `origin`, `negate`, `occupied_thresh`,
    /// `free_thresh`, optional `mode`), as map_server, Nav2's map_saver, slam_toolbox,
    /// Cartographer and GMapping save it.
    pub yaml: PathBuf,
    /// The line map (JSON) to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Spacing of the virtual scan positions over the free cells (m).
    #[arg(long, default_value_t = GridImportParams::default().scan_spacing)]
    pub scan_spacing: f64,
    /// Range of the virtual laser (m).
    #[arg(long, default_value_t = GridImportParams::default().max_range)]
    pub max_range: f64,
    /// Keep walls seen from at least this many scan positions.
    #[arg(long, default_value_t = GridImportParams::default().min_sightings)]
    pub min_sightings: u32,
    /// Configuration file (TOML): the line extraction parameters.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf map plot`.
#[derive(Debug, Args)]
pub struct MapPlotArgs {
    /// The line map (JSON).
    pub map: PathBuf,
    /// The SVG file to write.
    #[arg(long)]
    pub svg: PathBuf,
    /// A trajectory (TUM text) to draw over the map, named by its file; may be repeated.
    #[arg(long)]
    pub trajectory: Vec<PathBuf>,
}

/// The arguments of `ekf map compare`.
#[derive(Debug, Args)]
pub struct MapCompareArgs {
    /// The line map (JSON) to judge.
    pub map: PathBuf,
    /// The reference line map (JSON).
    #[arg(long)]
    pub reference: PathBuf,
    /// Move the map onto the reference first by a rigid alignment: ICP of its walls to the
    /// reference's, from the identity and, if a coarse search from any start puts the map
    /// elsewhere, from there too (the one that matches more is kept).
    #[arg(long)]
    pub align: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The arguments of `ekf map export-grid`.
#[derive(Debug, Args)]
pub struct MapExportGridArgs {
    /// The line map (JSON).
    pub map: PathBuf,
    /// The YAML file to write; the PGM image gets the same name with `.pgm`.
    #[arg(long)]
    pub out: PathBuf,
    /// Side of a cell (m).
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Free border around the walls' bounding box (m).
    #[arg(long, default_value_t = 1.0)]
    pub margin: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Which kind of CARMEN log a file is.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Flavour {
    Auto,
    Corrected,
    Plain,
}
