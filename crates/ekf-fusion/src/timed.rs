//! The time-ordered localizer: inputs pushed as they arrive, fused in stamp order.

use crate::fuser::{Forecast, Fused, Fuser};
use crate::reorder::{Reorder, TooLate};
use crate::{FusionError, Input};
use lrf_lines::StageClock;

/// One fused input, handed back by [`TimedLocalizer::next_ready`] and
/// [`TimedLocalizer::next_held`].
#[derive(Debug, Clone, PartialEq)]
pub struct Step<T> {
    /// Its stamp (ns).
    pub stamp_ns: u64,
    /// The input.
    pub input: Input,
    /// What the caller pushed with it.
    pub tag: T,
    /// What fusing it did.
    pub fused: Fused,
}

/// Inputs pushed in the order they arrive, each with its stamp and a tag of the caller's
/// (a topic and log time, say), fused in stamp order.
///
/// # What is buffered, and for how long
///
/// Each input is held until one stamped `max_lag` after it has been pushed (see
/// [`crate::reorder`]): then no input stamped before it can still come in time, and it is
/// fused at its own stamp. So a measurement up to `max_lag` older than the newest input
/// meets the state of its own time, and every later input is applied after it: the
/// estimate robot_localization's rewind-and-re-predict (`smooth_lagged_data`) gives, with
/// no state history to keep and no update ever done twice. An input stamped before one
/// already fused came more than `max_lag` late: it is dropped, counted
/// ([`crate::FusionCounts::too_late`]) and handed back in the error for the caller to
/// report. What is held is at most `max_lag` of inputs (at 50 Hz odometry and a 10 Hz
/// laser, 30 inputs for the default 0.5 s); the buffer's storage is reused, so once it
/// has held that much nothing is allocated to hold inputs.
///
/// # The pose now
///
/// The fused state trails the newest input by `max_lag`. [`pose_now`](Self::pose_now)
/// predicts it through the motion readings still held, as fusing them will (on a copy of
/// the filter, one prediction per held reading): what a robot acts on. A late
/// measurement costs nothing extra: it is fused once, in its place.
pub struct TimedLocalizer<T> {
    fuser: Fuser,
    order: Reorder<(Input, T)>,
}

impl<T> TimedLocalizer<T> {
    /// Fuses with `fuser`, holding inputs back by `max_lag_ns`.
    pub fn new(fuser: Fuser, max_lag_ns: u64) -> Self {
        Self {
            fuser,
            order: Reorder::new(max_lag_ns),
        }
    }

    /// The fuser: the filter, the map and the counts.
    pub fn fuser(&self) -> &Fuser {
        &self.fuser
    }

    /// The fuser, to change its filter between inputs ([`Fuser::localizer_mut`]).
    pub fn fuser_mut(&mut self) -> &mut Fuser {
        &mut self.fuser
    }

    /// Takes an input stamped `stamp_ns`. One stamped before an input already fused is
    /// refused and counted: more than the lag late.
    pub fn push(&mut self, stamp_ns: u64, input: Input, tag: T) -> Result<(), TooLate<(Input, T)>> {
        self.order.push(stamp_ns, (input, tag)).inspect_err(|_| {
            self.fuser.count_too_late();
        })
    }

    /// Fuses the next input whose turn has come (one stamped `max_lag` after it has been
    /// pushed), telling `clock` when a scan update's stages end; `None` if none has.
    pub fn next_ready(
        &mut self,
        clock: &mut impl StageClock,
    ) -> Option<Result<Step<T>, FusionError>> {
        let (stamp_ns, (input, tag)) = self.order.pop_ready()?;
        Some(self.fuse(stamp_ns, input, tag, clock))
    }

    /// Fuses the next held input regardless of the lag (when the inputs have ended).
    pub fn next_held(
        &mut self,
        clock: &mut impl StageClock,
    ) -> Option<Result<Step<T>, FusionError>> {
        let (stamp_ns, (input, tag)) = self.order.pop()?;
        Some(self.fuse(stamp_ns, input, tag, clock))
    }

    fn fuse(
        &mut self,
        stamp_ns: u64,
        input: Input,
        tag: T,
        clock: &mut impl StageClock,
    ) -> Result<Step<T>, FusionError> {
        let fused = self.fuser.fuse(stamp_ns, &input, clock)?;
        Ok(Step {
            stamp_ns,
            input,
            tag,
            fused,
        })
    }

    /// Inputs held, waiting for their turn.
    pub fn held(&self) -> usize {
        self.order.len()
    }

    /// The pose now: the fused state predicted through the motion readings held and then
    /// through `more` (readings not pushed yet, in stamp order, after the held ones), as
    /// fusing them would ([`Fuser::forecast`]). `None` until a motion step was fused.
    pub fn pose_now<'m>(
        &'m self,
        more: impl IntoIterator<Item = (u64, &'m Input)>,
    ) -> Result<Option<Forecast>, FusionError> {
        let held = self
            .order
            .held()
            .filter(|(_, (input, _))| input.is_motion())
            .map(|(stamp, (input, _))| (stamp, input));
        self.fuser.forecast(held.chain(more))
    }
}
