//! Loss detection and relocalization for the laser modes with a given map.
//!
//! # When the filter counts as lost
//!
//! * **A motion gap**: a scan arrives and the motion source's last message is older than
//!   twice its usual interval (a running mean of its message intervals), or it has said
//!   nothing since the scan before while it covers fewer than a quarter of the scan
//!   intervals anyway. Whatever the robot did meanwhile is unknown (seattle turns 80° in
//!   3 s without odometry, orebro has almost none at all): the laser decides. A laser
//!   faster than the motion source leaves some scan intervals without a motion message;
//!   those are no gap, as the next message's delta covers them.
//! * **No line fused**: [`LOST_AFTER_SCANS`] scans in a row each extracted at least two
//!   lines and fused none of them: the state no longer explains what the laser sees.
//!
//! # When the filter is checked
//!
//! While its heading's standard deviation is larger than the search's angle tolerance
//! ([`RelocalizeParams::angle_tolerance`], 3°), a scan's lines locate the robot better
//! than the filter does: the same search runs, and a clear, verified answer elsewhere
//! restarts the filter there (a relocalization without a loss). Odometry that turns
//! worse than its noise model says (csail's is off by up to 17° on a 60° turn) is caught so
//! before nearest-neighbour matching locks onto the wrong walls. A check whose search is
//! refused (ambiguous, or not verified) leaves the filter treated as lost, without a loss
//! counted, until a scan fixes the position again (at least [`MIN_VERIFIED_LINES`]
//! lines fused, two of them not parallel: walls on one side and the other of a corridor
//! agree with any place along it): meanwhile each scan searches a wider window. A loss
//! ends the same way when tracking alone regains the pose.
//!
//! # What is done then
//!
//! The map is searched for the pose from the scan's lines alone
//! ([`lrf_lines::relocalize()`]) within a window around the current estimate: `3σ` of its
//! position plus 2 m, plus 2 m for every further scan since the pose was last fixed (by
//! tracking, or a restart, confirmed or not); after [`GLOBAL_AFTER_SCANS`] such scans (and
//! from the start with `--global`), the whole map.
//!
//! While lost with odometry since the scan before, the search only nominates: its best
//! poses are tracked over the next scans (each predicted with the motion model and looked
//! for within its own uncertainty) and the one that explains those scans clearly better
//! than the others wins ([`crate::verification`]). After a motion
//! gap there is no odometry to carry them, and a check of a tracked estimate starts from
//! a pose the filter still trusts: there the search's own scan decides, its best pose
//! taken only when it wins clearly over every pose elsewhere
//! ([`lrf_lines::Relocalization::is_unambiguous`]). After a gap that answer is one
//! scan's word (a corridor's walls agree with many places along it; orebro's scans, 2 m
//! apart with no odometry between, were put 1.5 to 20 m off this way): the filter
//! restarts there but stays lost until a scan tracked from it by the motion model fixes
//! the position, as a loss ends by tracking alone. A search that finds the robot where
//! the estimate already was confirms it at once, unless that estimate was itself one
//! scan's answer.
//!
//! Either way, once the filter is restarted at the chosen pose (with the verified
//! candidate's own covariance, or the search's resolution for a single scan's answer), the
//! scan's lines must fuse at least [`MIN_VERIFIED_LINES`] of them there (the search has
//! already placed the robot; requiring two that are not parallel here delayed `--global`'s
//! lock-on in edmonton's open hall from scan 4 to 21); otherwise the filter is put back as
//! it was. A relocalization within [`RelocalizeParams::distinct_distance`] and
//! [`RelocalizeParams::distinct_angle`] of the estimate changes nothing. Every loss, its
//! end and every relocalization are reported with the scan ([`crate::ScanFused`]; `ekf
//! replay` writes them to `/ekf/diagnostics` as `ekf/tracking` and `ekf/relocalization`),
//! and the counts include the scans spent lost.

use alloc::vec::Vec;
use lrf_lines::{direction_diff, RelocalizeParams, SearchWindow};
use nalgebra::{Matrix3, Point2};

/// Scans in a row with lines but none fused before the filter counts as lost.
pub const LOST_AFTER_SCANS: u32 = 3;

/// Scans lost after which the search covers the whole map.
pub const GLOBAL_AFTER_SCANS: u32 = 10;

/// Lines a scan must fuse at a relocalized pose for it to be kept; while lost, tracking
/// counts as regained only when this many fused lines also fix the position
/// ([`fix_position`]).
pub const MIN_VERIFIED_LINES: usize = 2;

/// Whether lines with these normal directions (rad), fused together, fix the position:
/// at least [`MIN_VERIFIED_LINES`] of them, two whose directions differ by at least
/// `params.min_pair_angle` modulo π (parallel walls leave the position along them free,
/// as the search's line pairs do).
pub fn fix_position(normals: &[f64], params: &RelocalizeParams) -> bool {
    normals.len() >= MIN_VERIFIED_LINES
        && normals.iter().enumerate().any(|(i, a)| {
            normals[i + 1..]
                .iter()
                .any(|b| libm::fabs(direction_diff(*a, *b)) >= params.min_pair_angle)
        })
}

/// Whether the filter's heading (covariance `p`) is less certain than the search
/// resolves: `σ_θ > params.angle_tolerance`.
pub fn uncertain(p: &Matrix3<f64>, params: &RelocalizeParams) -> bool {
    libm::sqrt(p[(2, 2)].max(0.0)) > params.angle_tolerance
}

/// Losses and relocalizations of a run, for its summary.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TrackingCounts {
    /// Scans that began a loss (a motion gap, or [`LOST_AFTER_SCANS`] unfused scans).
    pub losses: u64,
    /// Of those, motion gaps.
    pub motion_gaps: u64,
    /// Relocalizations that moved the filter (after a loss, or a check while the heading
    /// was uncertain), confirmed or not.
    pub relocalizations: u64,
    /// Searches run.
    pub searches: u64,
    /// Searches whose best pose was ambiguous or failed verification.
    pub refused: u64,
    /// Scans that ended with the filter lost (from a loss until it was regained) or
    /// unconfirmed (a check's search refused while the heading was uncertain, until lines
    /// fused again; or restarted at one scan's answer after a motion gap, until a scan
    /// tracked from it fixed the position): their poses are the filter's guess, not a
    /// tracked estimate.
    pub scans_lost: u64,
    /// Scans the filter had been lost for when the log ended (0: tracking).
    pub lost_at_end: u32,
    /// Stamps (ns) of the first relocalizations.
    pub first_relocalizations_ns: Vec<u64>,
    /// With global localization, the scan (1-based) at which the search locked on.
    pub locked_on_scan: Option<u64>,
}

/// The loss monitor's state between scans.
#[derive(Debug, Clone, Default)]
pub struct Tracking {
    /// Whether it runs: with a given map. A first-scan map (the paper's) is the room in
    /// view and carries its own placement error in the filter, which a restart would
    /// break, so there the filter is left as it is.
    pub enabled: bool,
    /// A motion message came since the last scan.
    pub motion_since_scan: bool,
    /// The odometry jumped since the last scan (a step refused as a jump, see
    /// [`crate::wheels::JUMP_FACTOR`]).
    pub motion_jumped: bool,
    /// The motion source has spoken at all.
    pub motion_seen: bool,
    /// Time of the last motion message (ns).
    pub last_motion_ns: Option<u64>,
    /// Scans in a row with lines and none fused.
    pub unfused: u32,
    /// Scans spent lost (0: tracking), or unconfirmed after a refused check or a
    /// restart at one scan's answer.
    pub lost_for: u32,
    /// Scans since the filter's pose was last fixed (a restart, confirmed or not, or
    /// tracking): how far the search looks ([`Tracking::window`]).
    pub since_fix: u32,
    /// A loss was declared (a motion gap, unfused scans, or the start of a global
    /// localization) and has not ended: its end is reported.
    pub declared: bool,
    /// Started without a pose (global localization) and not yet locked on.
    pub unlocked: bool,
    /// A search's candidates being judged over the next scans.
    pub verification: Option<crate::verification::Verification>,
    /// Laser scans seen.
    pub scans: u64,
    /// Running mean of the motion source's message intervals (ns).
    motion_interval_ns: Option<f64>,
    /// Scan intervals (after the motion source first spoke) and how many had a motion
    /// message.
    intervals: u64,
    covered: u64,
}

impl Tracking {
    /// A monitor that runs if `enabled`.
    pub fn new(enabled: bool) -> Self {
        Self {
            enabled,
            ..Self::default()
        }
    }

    /// A monitor for global localization: lost from the start, searching the whole map.
    pub fn global() -> Self {
        Self {
            enabled: true,
            unlocked: true,
            lost_for: GLOBAL_AFTER_SCANS,
            since_fix: GLOBAL_AFTER_SCANS,
            declared: true,
            ..Self::default()
        }
    }

    /// The search found the filter's pose (or moved the filter there): tracking again.
    pub fn locked(&mut self, counts: &mut TrackingCounts) {
        if self.unlocked {
            counts.locked_on_scan = Some(self.scans);
            self.unlocked = false;
        }
        self.lost_for = 0;
        self.since_fix = 0;
        self.unfused = 0;
        self.declared = false;
    }

    /// The filter restarted at one scan's answer after a motion gap: still lost (the
    /// loss stays declared, and this scan counts as lost) until a scan tracked from it
    /// fixes the position; the search looks around it ([`Tracking::since_fix`] 0).
    pub fn unconfirmed(&mut self) {
        self.lost_for += 1;
        self.since_fix = 0;
        self.unfused = 0;
    }

    /// Another scan ended lost: one more scan since the last fix.
    pub fn still_lost(&mut self) {
        self.lost_for += 1;
        self.since_fix += 1;
    }

    /// A motion message at `t_ns`.
    pub fn motion(&mut self, t_ns: u64) {
        if let Some(last) = self.last_motion_ns.filter(|&l| t_ns > l) {
            let dt = (t_ns - last) as f64;
            self.motion_interval_ns =
                Some(self.motion_interval_ns.map_or(dt, |m| 0.9 * m + 0.1 * dt));
        }
        self.motion_since_scan = true;
        self.motion_seen = true;
        self.last_motion_ns = Some(t_ns);
    }

    /// Counts the scan at `t_ns` and says whether it follows a motion gap; resets the
    /// per-scan flag.
    pub fn gap_before_scan(&mut self, t_ns: u64) -> bool {
        self.scans += 1;
        if !self.motion_seen {
            return false;
        }
        let covered = core::mem::replace(&mut self.motion_since_scan, false);
        let jumped = core::mem::replace(&mut self.motion_jumped, false);
        self.intervals += 1;
        self.covered += u64::from(covered);
        let rarely_covers = 4 * self.covered < self.intervals;
        let stale = match (self.last_motion_ns, self.motion_interval_ns) {
            (Some(last), Some(interval)) => t_ns.saturating_sub(last) as f64 > 2.0 * interval,
            _ => false,
        };
        jumped || stale || (!covered && rarely_covers)
    }

    /// Notes a scan's outcome; returns whether the filter is lost now.
    pub fn scan_fused(&mut self, extracted: usize, fused: usize) -> bool {
        if fused > 0 {
            self.unfused = 0;
        } else if extracted >= 2 {
            self.unfused += 1;
        }
        self.unfused >= LOST_AFTER_SCANS
    }

    /// The search window around `center` with position covariance trace `var_xy`. A
    /// search of the whole map costs about 12 ms on a 500-wall map (criterion bench
    /// `relocalize global, 500 walls`), within a 10 Hz laser's period, so it runs on
    /// every lost scan.
    pub fn window(&self, center: Point2<f64>, var_xy: f64) -> SearchWindow {
        if self.since_fix >= GLOBAL_AFTER_SCANS {
            return SearchWindow::global();
        }
        SearchWindow::around(
            center,
            3.0 * libm::sqrt(var_xy.max(0.0)) + 2.0 * f64::from(1 + self.since_fix),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gap_is_a_motion_source_silent_for_twice_its_interval() {
        let mut t = Tracking::default();
        assert!(!t.gap_before_scan(5), "no motion source yet: no gap");
        for k in 1..=10 {
            t.motion(k * 50);
        }
        assert!(!t.gap_before_scan(520), "20 after the last message");
        assert!(
            !t.gap_before_scan(540),
            "a laser faster than the motion source"
        );
        assert!(
            t.gap_before_scan(601),
            "silent for over twice its 50 interval"
        );
        t.motion(610);
        assert!(!t.gap_before_scan(620));
    }

    #[test]
    fn a_motion_source_that_rarely_covers_a_scan_interval_leaves_each_uncovered_one_a_gap() {
        let mut t = Tracking::default();
        t.motion(0);
        t.motion(1_000);
        // Scans every 10 after that, the motion source silent (its interval 1000).
        let gaps: Vec<bool> = (1..=6).map(|k| t.gap_before_scan(1_000 + 10 * k)).collect();
        assert_eq!(gaps, [false, false, false, false, true, true]);
    }

    #[test]
    fn the_filter_is_lost_after_three_scans_with_lines_and_none_fused() {
        let mut t = Tracking::default();
        assert!(!t.scan_fused(5, 0));
        assert!(!t.scan_fused(1, 0), "one line: not counted");
        assert!(!t.scan_fused(4, 0));
        assert!(t.scan_fused(3, 0));
        assert!(!t.scan_fused(3, 1), "a fused line ends it");
    }

    #[test]
    fn only_lines_that_are_not_parallel_fix_the_position() {
        let params = RelocalizeParams::default();
        let deg = |d: f64| d.to_radians();
        assert!(!fix_position(&[], &params));
        assert!(!fix_position(&[deg(10.0)], &params), "one line");
        // The two walls of a corridor: normals opposite, the same direction.
        assert!(!fix_position(&[deg(90.0), deg(-90.0)], &params));
        assert!(!fix_position(&[deg(90.0), deg(-90.0), deg(119.0)], &params));
        assert!(fix_position(&[deg(90.0), deg(-90.0), deg(121.0)], &params));
        assert!(fix_position(&[deg(0.0), deg(90.0)], &params), "a corner");
        // Across the ±π seam: 175° and −150° are 35° apart.
        assert!(fix_position(&[deg(175.0), deg(-150.0)], &params));
        assert!(!fix_position(&[deg(175.0), deg(-170.0)], &params));
    }

    #[test]
    fn a_heading_less_certain_than_the_search_resolves_is_checked() {
        let params = RelocalizeParams::default();
        let var = |deg: f64| {
            Matrix3::from_diagonal(&nalgebra::Vector3::new(
                0.01,
                0.01,
                deg.to_radians().powi(2),
            ))
        };
        assert!(!uncertain(&var(2.9), &params));
        assert!(uncertain(&var(3.1), &params));
    }

    #[test]
    fn the_window_grows_while_lost_then_covers_the_map() {
        let mut t = Tracking::default();
        let c = Point2::new(1.0, 2.0);
        assert!((t.window(c, 0.04).radius - 2.6).abs() < 1e-12);
        t.still_lost();
        t.still_lost();
        assert!((t.window(c, 0.04).radius - 6.6).abs() < 1e-12);
        for _ in 2..GLOBAL_AFTER_SCANS {
            t.still_lost();
        }
        assert_eq!(t.window(c, 0.04), SearchWindow::global());
        t.still_lost();
        assert_eq!(t.window(c, 0.04), SearchWindow::global());
    }

    #[test]
    fn a_restart_at_one_scans_answer_is_still_lost_but_searches_from_there() {
        let mut t = Tracking::default();
        let c = Point2::new(1.0, 2.0);
        for _ in 0..GLOBAL_AFTER_SCANS {
            t.still_lost();
        }
        t.unconfirmed();
        assert_eq!(
            t.lost_for,
            GLOBAL_AFTER_SCANS + 1,
            "still lost, and counting"
        );
        assert!((t.window(c, 0.04).radius - 2.6).abs() < 1e-12);
        t.still_lost();
        assert_eq!(t.lost_for, GLOBAL_AFTER_SCANS + 2);
        assert!((t.window(c, 0.04).radius - 4.6).abs() < 1e-12);
        t.locked(&mut TrackingCounts::default());
        assert_eq!((t.lost_for, t.since_fix), (0, 0));
    }
}
