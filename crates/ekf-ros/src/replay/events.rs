//! What a replay marks on its picture (`ekf replay --svg`): the scans whose lines were
//! refused, the compass headings the gate rejected, the losses it declared and the
//! relocalizations, each at its stamp. Kept only when trajectories are kept.

/// An event of a replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplayEvent {
    /// A scan had lines the gate rejected or the association refused as ambiguous.
    LinesRefused,
    /// A compass heading was rejected by its chi-square gate.
    CompassRejected,
    /// The filter declared itself lost (`ekf/tracking`).
    Lost,
    /// The filter restarted at a pose the map search found (`ekf/relocalization`).
    Relocalized,
}

impl ReplayEvent {
    /// Every kind, in the order a legend lists them.
    pub const ALL: [ReplayEvent; 4] = [
        ReplayEvent::LinesRefused,
        ReplayEvent::CompassRejected,
        ReplayEvent::Lost,
        ReplayEvent::Relocalized,
    ];

    /// The name in a legend.
    pub fn name(self) -> &'static str {
        match self {
            ReplayEvent::LinesRefused => "lines refused",
            ReplayEvent::CompassRejected => "compass rejected",
            ReplayEvent::Lost => "lost",
            ReplayEvent::Relocalized => "relocalized",
        }
    }
}

/// The events and the lost scans of a replay, as they happen.
#[derive(Debug, Clone, Default)]
pub(crate) struct EventLog {
    /// Each event with its stamp (ns), in the order they happened.
    pub events: Vec<(u64, ReplayEvent)>,
    /// Stamps of the scans that ended with the filter lost.
    pub lost_scans: Vec<u64>,
}
