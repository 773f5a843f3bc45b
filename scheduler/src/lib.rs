//! Physics-agnostic ordering of tent pitches on an advancing front.
//!
//! The scheduler knows vertex times only; what a pitch does (tent height, patch solve) is the
//! caller's callback. This release drives one thread in order of increasing front time: the
//! earliest vertex of the front is always a local minimum, so it can always be pitched, and the
//! order depends only on the times and vertex ids (ties go to the smaller id), never on timing.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// Index of a front vertex.
pub type VertexId = u32;

/// What stopped a run before the front reached the end time.
#[derive(Debug, thiserror::Error)]
pub enum RunError<E> {
    /// The callback did not advance the vertex: the pitching rule lost progress.
    #[error("no progress: pitching vertex {vertex} at t = {time} s did not advance it")]
    Stalled {
        /// The vertex that did not move.
        vertex: VertexId,
        /// Its time, seconds.
        time: f64,
    },
    /// The callback failed.
    #[error(transparent)]
    Pitch(E),
}

/// Counts of a completed run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunStats {
    /// Tents pitched.
    pub tents: u64,
}

/// A front time with a total order (times are finite).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Time(f64);

impl Eq for Time {}

impl PartialOrd for Time {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Time {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Advances every vertex from `times` (seconds) to `t_end` on one thread. `pitch(v)` must pitch
/// a tent at `v`, which is then a minimum of the whole front, and return its new time; it is
/// called until every vertex has reached `t_end`.
pub fn run_serial<E>(
    times: &[f64],
    t_end: f64,
    mut pitch: impl FnMut(VertexId) -> Result<f64, E>,
) -> Result<RunStats, RunError<E>> {
    let mut queue: BinaryHeap<Reverse<(Time, VertexId)>> = times
        .iter()
        .enumerate()
        .filter(|&(_, &t)| t < t_end)
        .map(|(v, &t)| Reverse((Time(t), v as VertexId)))
        .collect();
    let mut stats = RunStats::default();
    while let Some(Reverse((Time(time), vertex))) = queue.pop() {
        let next = pitch(vertex).map_err(RunError::Pitch)?;
        if next.partial_cmp(&time) != Some(Ordering::Greater) {
            return Err(RunError::Stalled { vertex, time });
        }
        stats.tents += 1;
        if next < t_end {
            queue.push(Reverse((Time(next), vertex)));
        }
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pitches_in_time_order_until_the_end() {
        let mut times = vec![0.0, 0.5, 0.0];
        let mut order = Vec::new();
        let stats = run_serial::<()>(&times.clone(), 1.0, |v| {
            order.push(v);
            let min = times.iter().copied().fold(f64::INFINITY, f64::min);
            assert_eq!(times[v as usize], min, "pitched vertex is a front minimum");
            times[v as usize] = (times[v as usize] + 0.4).min(1.0);
            Ok(times[v as usize])
        })
        .unwrap();
        assert_eq!(order, [0, 2, 0, 2, 1, 0, 2, 1]);
        assert_eq!(stats.tents, 8);
        assert!(times.iter().all(|&t| t == 1.0));
    }

    #[test]
    fn reports_a_stall_and_callback_errors() {
        let err = run_serial::<()>(&[0.0], 1.0, |_| Ok(0.0)).unwrap_err();
        assert!(matches!(
            err,
            RunError::Stalled {
                vertex: 0,
                time: 0.0
            }
        ));
        let err = run_serial(&[0.0], 1.0, |_| Err("boom")).unwrap_err();
        assert!(matches!(err, RunError::Pitch("boom")));
    }
}
