//! A fixed-lag reordering buffer: items pushed in arrival order come out in stamp order.
//!
//! A robot computer hands on a scan a few hundred milliseconds after the laser took it (its
//! stamp), after odometry that came later; fused in arrival order, the scan would meet a
//! state that has moved on. So each item is held back until no item stamped before it can
//! still arrive — until one stamped `lag` later has been pushed — and handed on in stamp
//! order (ties in arrival order). An item stamped before one already handed on came more
//! than the lag late: it is refused. What is held is at most `lag` of the inputs.

use alloc::collections::VecDeque;

/// The reordering buffer (see the module documentation). Held items are kept sorted by
/// stamp, ties in arrival order; a late item is inserted in its place, shifting the few
/// held after it. Once the buffer has held its most, nothing is allocated.
pub struct Reorder<T> {
    lag_ns: u64,
    held: VecDeque<(u64, T)>,
    /// Latest stamp pushed.
    newest: u64,
    /// Stamp of the last item handed on.
    released: Option<u64>,
}

/// An item refused by [`Reorder::push`]: it came after an item stamped later than it was
/// handed on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TooLate<T> {
    /// The item, given back.
    pub item: T,
    /// Its stamp (ns).
    pub stamp: u64,
    /// The stamp of the item handed on before it came (ns).
    pub after: u64,
}

impl<T> Reorder<T> {
    /// A buffer holding items back by `lag_ns`.
    pub fn new(lag_ns: u64) -> Self {
        Self {
            lag_ns,
            held: VecDeque::new(),
            newest: 0,
            released: None,
        }
    }

    /// The lag (ns).
    pub fn lag_ns(&self) -> u64 {
        self.lag_ns
    }

    /// Sets the lag (ns) from now on: a live caller learns its devices' latencies as they
    /// connect.
    pub fn set_lag_ns(&mut self, lag_ns: u64) {
        self.lag_ns = lag_ns;
    }

    /// Time has reached `now_ns` without an item: a live caller's clock, which tells as
    /// well as a pushed item that nothing stamped more than the lag before it can still
    /// come. Items whose turn that brings come out of [`pop_ready`](Self::pop_ready).
    pub fn advance_to(&mut self, now_ns: u64) {
        self.newest = self.newest.max(now_ns);
    }

    /// Takes an item stamped `stamp`; refuses it if an item stamped after it was handed on
    /// already (it came more than the lag late, too late to be handed on in order).
    pub fn push(&mut self, stamp: u64, item: T) -> Result<(), TooLate<T>> {
        if let Some(after) = self.released.filter(|&r| stamp < r) {
            return Err(TooLate { item, stamp, after });
        }
        self.newest = self.newest.max(stamp);
        // After every held item stamped at or before it: ties stay in arrival order.
        let at = self.held.partition_point(|(s, _)| *s <= stamp);
        self.held.insert(at, (stamp, item));
        Ok(())
    }

    /// The next item whose turn has come, with its stamp: the earliest stamp, once an item
    /// stamped at least the lag after it has been pushed.
    pub fn pop_ready(&mut self) -> Option<(u64, T)> {
        let (first, _) = self.held.front()?;
        if first.saturating_add(self.lag_ns) > self.newest {
            return None;
        }
        self.pop()
    }

    /// The next item with its stamp, regardless of the lag (at the end of the inputs).
    pub fn pop(&mut self) -> Option<(u64, T)> {
        let (stamp, item) = self.held.pop_front()?;
        self.released = Some(stamp);
        Some((stamp, item))
    }

    /// The held items with their stamps, in the order they will be handed on.
    pub fn held(&self) -> impl Iterator<Item = (u64, &T)> {
        self.held.iter().map(|(stamp, item)| (*stamp, item))
    }

    /// How many items are held.
    pub fn len(&self) -> usize {
        self.held.len()
    }

    /// Whether nothing is held.
    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    const MS: u64 = 1_000_000;

    #[test]
    fn late_items_come_out_in_stamp_order_at_their_stamps() {
        let mut r = Reorder::new(500 * MS);
        // Arrived in this order; the 1000 ms one 350 ms late.
        for (arrived, stamp) in [(1100, 1100), (1200, 1200), (1350, 1000), (1400, 1400)] {
            r.push(stamp * MS, arrived).unwrap();
        }
        assert_eq!(r.pop_ready(), None, "1400 - 1000 < 500");
        r.push(1500 * MS, 1500).unwrap();
        assert_eq!(r.pop_ready(), Some((1000 * MS, 1350)));
        assert_eq!(r.pop_ready(), None);
        let rest: Vec<u64> = core::iter::from_fn(|| r.pop())
            .map(|(stamp, _)| stamp / MS)
            .collect();
        assert_eq!(rest, [1100, 1200, 1400, 1500]);
    }

    #[test]
    fn ties_come_out_in_arrival_order() {
        let mut r = Reorder::new(0);
        for k in 0..5 {
            r.push(7, k).unwrap();
        }
        let order: Vec<i32> = core::iter::from_fn(|| r.pop()).map(|(_, k)| k).collect();
        assert_eq!(order, [0, 1, 2, 3, 4]);
    }

    #[test]
    fn an_item_older_than_what_was_handed_on_is_refused() {
        let mut r = Reorder::new(100 * MS);
        r.push(1000 * MS, "a").unwrap();
        r.push(1200 * MS, "b").unwrap();
        assert!(r.pop_ready().is_some());
        let late = r.push(900 * MS, "late").unwrap_err();
        assert_eq!(
            late,
            TooLate {
                item: "late",
                stamp: 900 * MS,
                after: 1000 * MS,
            }
        );
        assert!(r.push(1000 * MS, "c").is_ok(), "the same stamp is not late");
    }

    #[test]
    fn a_clock_releases_items_as_a_later_item_would() {
        let mut r = Reorder::new(300 * MS);
        r.push(1000 * MS, 'a').unwrap();
        r.push(1100 * MS, 'b').unwrap();
        r.advance_to(1299 * MS);
        assert_eq!(r.pop_ready(), None);
        r.advance_to(1350 * MS);
        assert_eq!(r.pop_ready(), Some((1000 * MS, 'a')));
        assert_eq!(r.pop_ready(), None);
        r.set_lag_ns(200 * MS);
        assert_eq!(r.pop_ready(), Some((1100 * MS, 'b')));
        r.advance_to(1000 * MS);
        assert!(r.push(1200 * MS, 'c').is_ok(), "time never runs back");
        assert_eq!(r.pop_ready(), None);
    }

    proptest::proptest! {
        /// Whatever the arrival order, what comes out is in stamp order, and every item
        /// comes out once or is refused as too late; within the lag nothing is refused.
        #[test]
        fn output_is_sorted_and_nothing_within_the_lag_is_lost(
            delays in proptest::collection::vec(0u64..400, 1..200),
        ) {
            // Item k is stamped 10k ms and arrives delays[k] ms later.
            let mut arrivals: Vec<(u64, u64)> = delays
                .iter()
                .enumerate()
                .map(|(k, d)| (10 * k as u64 + d, 10 * k as u64))
                .collect();
            arrivals.sort();
            let mut r = Reorder::new(400 * MS);
            let mut out = Vec::new();
            for &(_, stamp) in &arrivals {
                proptest::prop_assert!(r.push(stamp * MS, stamp).is_ok());
                while let Some((s, _)) = r.pop_ready() {
                    out.push(s);
                }
            }
            while let Some((s, _)) = r.pop() {
                out.push(s);
            }
            proptest::prop_assert_eq!(out.len(), delays.len());
            proptest::prop_assert!(out.windows(2).all(|w| w[0] <= w[1]));
        }
    }
}
