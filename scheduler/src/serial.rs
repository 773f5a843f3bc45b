//! The reference serial order: one thread, always the earliest vertex of the front.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use crate::{RunError, VertexId};

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

/// Advances every vertex from `times` (seconds) to `t_end` on the calling thread, always pitching
/// the earliest vertex of the front (ties to the smaller id), which is always a local minimum.
/// `pitch(v)` pitches a tent at `v` and returns its new time. Returns the number of tents.
pub fn run_serial<E>(
    times: &[f64],
    t_end: f64,
    mut pitch: impl FnMut(VertexId) -> Result<f64, E>,
) -> Result<u64, RunError<E>> {
    let mut queue: BinaryHeap<Reverse<(Time, VertexId)>> = times
        .iter()
        .enumerate()
        .filter(|&(_, &t)| t < t_end)
        .map(|(v, &t)| Reverse((Time(t), v as VertexId)))
        .collect();
    let mut tents = 0;
    while let Some(Reverse((Time(time), vertex))) = queue.pop() {
        let next = pitch(vertex).map_err(RunError::Work)?;
        if next.partial_cmp(&time) != Some(Ordering::Greater) {
            return Err(RunError::Stalled {
                remaining: queue.len() + 1,
            });
        }
        tents += 1;
        if next < t_end {
            queue.push(Reverse((Time(next), vertex)));
        }
    }
    Ok(tents)
}

#[cfg(all(test, not(feature = "loom")))]
mod tests {
    use super::*;

    #[test]
    fn pitches_in_time_order_until_the_end() {
        let mut times = vec![0.0, 0.5, 0.0];
        let mut order = Vec::new();
        let tents = run_serial::<()>(&times.clone(), 1.0, |v| {
            order.push(v);
            let min = times.iter().copied().fold(f64::INFINITY, f64::min);
            assert_eq!(times[v as usize], min, "pitched vertex is a front minimum");
            times[v as usize] = (times[v as usize] + 0.4).min(1.0);
            Ok(times[v as usize])
        })
        .unwrap();
        assert_eq!(order, [0, 2, 0, 2, 1, 0, 2, 1]);
        assert_eq!(tents, 8);
        assert!(times.iter().all(|&t| t == 1.0));
    }

    #[test]
    fn reports_a_stall_and_callback_errors() {
        let err = run_serial::<()>(&[0.0], 1.0, |_| Ok(0.0)).unwrap_err();
        assert!(matches!(err, RunError::Stalled { remaining: 1 }));
        let err = run_serial(&[0.0], 1.0, |_| Err("boom")).unwrap_err();
        assert!(matches!(err, RunError::Work("boom")));
    }
}
