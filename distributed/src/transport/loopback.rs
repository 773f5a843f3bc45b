//! The in-process transport: ranks are threads of one process, each with a mailbox.
//!
//! Every message gets a seeded random delay in `[0, max_delay]` before its receiver can take
//! it, so messages from different senders arrive in an order that differs from the order they
//! were sent, and with `fifo` off messages of one sender to one receiver may overtake each
//! other too. The delays come from each sender's own generator seeded from the run's seed and
//! its rank; thread timing adds its own variation on top. A receiver with nothing deliverable
//! waits on a condition variable until the next message is due, a send wakes it, or its
//! timeout ends. [`Transport::sum`] meets the other ranks at a shared tally; a rank waiting
//! there gives up when an [`Message::Abort`] reaches its mailbox.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use super::{Message, Transport, TransportError};
use crate::partition::Rank;
use crate::rng::SplitMix64;

/// How [`Loopback`] delays messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopbackOptions {
    /// Seed of the delays.
    pub seed: u64,
    /// Longest delay of a message; zero delivers at once.
    pub max_delay: Duration,
    /// Keep messages from one sender to one receiver in order (as MPI does).
    pub fifo: bool,
}

/// A message on its way, ordered by when it may be taken, then by when it was sent.
#[derive(Debug)]
struct Pending {
    due: Instant,
    sequence: u64,
    from: Rank,
    message: Message,
}

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pending {
    /// Reversed, so that [`BinaryHeap`] pops the earliest.
    fn cmp(&self, other: &Self) -> Ordering {
        (other.due, other.sequence).cmp(&(self.due, self.sequence))
    }
}

/// A rank's incoming messages.
#[derive(Debug)]
struct Inbox {
    pending: BinaryHeap<Pending>,
    /// Per sender, when its latest message is due (for FIFO order).
    latest: Vec<Option<Instant>>,
    sequence: u64,
}

#[derive(Debug)]
struct Mailbox {
    inbox: Mutex<Inbox>,
    arrived: Condvar,
}

impl Mailbox {
    fn lock(&self) -> MutexGuard<'_, Inbox> {
        // A rank that panicked holding the lock left a consistent inbox (pushes and pops are
        // single calls), so the poison is ignored.
        self.inbox.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The ranks' meeting point for the collectives ([`Transport::all_gather`], and
/// [`Transport::sum`] over it): what each rank gave in the round being collected.
#[derive(Debug, Default)]
struct Tally {
    /// Rounds completed so far.
    round: u64,
    /// Ranks that have given their bytes to this round.
    arrived: usize,
    /// By rank, what it gave to this round.
    given: Vec<Vec<u8>>,
    /// What the ranks gave to the last completed round.
    last: Arc<[Vec<u8>]>,
}

/// How often a rank waiting at the tally looks for an abort in its mailbox.
const TALLY_POLL: Duration = Duration::from_millis(5);

/// One rank's end of an in-process transport (see the module docs).
#[derive(Debug)]
pub struct Loopback {
    rank: Rank,
    mailboxes: Arc<[Mailbox]>,
    tally: Arc<(Mutex<Tally>, Condvar)>,
    delays: SplitMix64,
    options: LoopbackOptions,
}

impl Loopback {
    /// The ends of a transport between `ranks` ranks, by rank.
    pub fn connect(ranks: usize, options: LoopbackOptions) -> Vec<Loopback> {
        let mailboxes: Arc<[Mailbox]> = (0..ranks)
            .map(|_| Mailbox {
                inbox: Mutex::new(Inbox {
                    pending: BinaryHeap::new(),
                    latest: vec![None; ranks],
                    sequence: 0,
                }),
                arrived: Condvar::new(),
            })
            .collect();
        let tally = Arc::new((Mutex::new(Tally::default()), Condvar::new()));
        (0..ranks)
            .map(|rank| Loopback {
                rank: rank as Rank,
                mailboxes: Arc::clone(&mailboxes),
                tally: Arc::clone(&tally),
                delays: SplitMix64::new(
                    options.seed ^ (rank as u64 + 1).wrapping_mul(0xa076_1d64_78bd_642f),
                ),
                options,
            })
            .collect()
    }
}

impl Transport for Loopback {
    fn rank(&self) -> Rank {
        self.rank
    }

    fn ranks(&self) -> usize {
        self.mailboxes.len()
    }

    fn send(&mut self, to: Rank, message: Message) -> Result<(), TransportError> {
        let ranks = self.mailboxes.len();
        let mailbox = self
            .mailboxes
            .get(to as usize)
            .ok_or(TransportError::NoSuchRank { to, ranks })?;
        let max = u64::try_from(self.options.max_delay.as_nanos()).unwrap_or(u64::MAX);
        let delay = match max {
            0 => 0,
            _ => self.delays.next_u64() % (max + 1),
        };
        let mut due = Instant::now() + Duration::from_nanos(delay);
        let mut inbox = mailbox.lock();
        let latest = &mut inbox.latest[self.rank as usize];
        if self.options.fifo {
            due = latest.map_or(due, |l| l.max(due));
        }
        *latest = Some(due);
        inbox.sequence += 1;
        let sequence = inbox.sequence;
        inbox.pending.push(Pending {
            due,
            sequence,
            from: self.rank,
            message,
        });
        drop(inbox);
        mailbox.arrived.notify_one();
        Ok(())
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<(Rank, Message)>, TransportError> {
        let mailbox = &self.mailboxes[self.rank as usize];
        let deadline = Instant::now() + timeout;
        let mut inbox = mailbox.lock();
        loop {
            let now = Instant::now();
            let wake = match inbox.pending.peek() {
                Some(p) if p.due <= now => {
                    let p = inbox.pending.pop().expect("peeked");
                    return Ok(Some((p.from, p.message)));
                }
                Some(p) => p.due.min(deadline),
                None => deadline,
            };
            if now >= deadline {
                return Ok(None);
            }
            inbox = mailbox
                .arrived
                .wait_timeout(inbox, wake - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    fn is_fifo(&self) -> bool {
        self.options.fifo
    }

    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError> {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let given = self.all_gather(bytes)?;
        let mut sums = vec![0u64; values.len()];
        for bytes in &given {
            for (sum, chunk) in sums.iter_mut().zip(bytes.chunks_exact(8)) {
                *sum += u64::from_le_bytes(chunk.try_into().expect("8 bytes"));
            }
        }
        Ok(sums)
    }

    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError> {
        let ranks = self.mailboxes.len();
        let (tally, met) = &*self.tally;
        let lock = || tally.lock().unwrap_or_else(|e| e.into_inner());
        let mut t = lock();
        if t.arrived == 0 {
            t.given = vec![Vec::new(); ranks];
        }
        t.given[self.rank as usize] = bytes;
        t.arrived += 1;
        if t.arrived == ranks {
            t.arrived = 0;
            t.round += 1;
            t.last = std::mem::take(&mut t.given).into();
            met.notify_all();
            return Ok(t.last.to_vec());
        }
        let round = t.round;
        while t.round == round {
            t = met
                .wait_timeout(t, TALLY_POLL)
                .unwrap_or_else(|e| e.into_inner())
                .0;
            if t.round != round {
                break;
            }
            drop(t);
            let inbox = self.mailboxes[self.rank as usize].lock();
            let abort = inbox.pending.iter().find(|p| p.message == Message::Abort);
            if let Some(p) = abort {
                return Err(TransportError::Aborted { by: p.from });
            }
            drop(inbox);
            t = lock();
        }
        Ok(t.last.to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(fifo: bool, max_delay_us: u64) -> LoopbackOptions {
        LoopbackOptions {
            seed: 7,
            max_delay: Duration::from_micros(max_delay_us),
            fifo,
        }
    }

    /// Sends `0..n` as done counts from every other rank to rank 0 on threads, `pause` apart,
    /// and returns what rank 0 received.
    fn exchange(
        ranks: usize,
        n: u64,
        pause: Duration,
        options: LoopbackOptions,
    ) -> Vec<(Rank, u64)> {
        let mut ends = Loopback::connect(ranks, options);
        let mut receiver = ends.remove(0);
        std::thread::scope(|s| {
            for mut end in ends {
                s.spawn(move || {
                    for sent in 0..n {
                        end.send(0, Message::Done { sent }).unwrap();
                        std::thread::sleep(pause);
                    }
                });
            }
            let mut got = Vec::new();
            while got.len() < (ranks - 1) * n as usize {
                match receiver.receive(Duration::from_secs(5)).unwrap() {
                    Some((from, Message::Done { sent })) => got.push((from, sent)),
                    other => panic!("unexpected {other:?}"),
                }
            }
            assert_eq!(receiver.receive(Duration::ZERO).unwrap(), None);
            got
        })
    }

    #[test]
    fn fifo_keeps_each_senders_order_and_mixes_senders() {
        let got = exchange(4, 100, Duration::from_micros(20), options(true, 500));
        for from in 1..4 {
            let seq: Vec<u64> = got.iter().filter(|m| m.0 == from).map(|m| m.1).collect();
            assert_eq!(seq, (0..100).collect::<Vec<_>>(), "from {from}");
        }
        let switches = got.windows(2).filter(|w| w[0].0 != w[1].0).count();
        assert!(switches > 20, "senders interleave: {switches}");
    }

    #[test]
    fn without_fifo_one_senders_messages_overtake_each_other() {
        let got = exchange(2, 300, Duration::ZERO, options(false, 300));
        let mut seq: Vec<u64> = got.iter().map(|m| m.1).collect();
        let inversions = seq.windows(2).filter(|w| w[0] > w[1]).count();
        assert!(inversions > 10, "{inversions}");
        seq.sort_unstable();
        assert_eq!(seq, (0..300).collect::<Vec<_>>(), "none lost or doubled");
    }

    #[test]
    fn receive_waits_for_a_due_message_and_times_out_when_none_comes() {
        let mut ends = Loopback::connect(2, options(true, 0));
        let start = Instant::now();
        assert_eq!(ends[0].receive(Duration::from_millis(20)).unwrap(), None);
        assert!(start.elapsed() >= Duration::from_millis(20));
        ends[1].send(0, Message::Abort).unwrap();
        assert_eq!(
            ends[0].receive(Duration::from_secs(1)).unwrap(),
            Some((1, Message::Abort))
        );
        assert_eq!(
            ends[0].send(2, Message::Abort),
            Err(TransportError::NoSuchRank { to: 2, ranks: 2 })
        );
        assert!(ends[0].is_fifo() && ends[0].ranks() == 2 && ends[1].rank() == 1);
    }

    #[test]
    fn every_rank_gathers_what_each_gave_by_rank_round_after_round() {
        let ends = Loopback::connect(3, options(true, 0));
        let gathered: Vec<Vec<Vec<Vec<u8>>>> = std::thread::scope(|s| {
            let handles: Vec<_> = (ends.into_iter())
                .map(|mut end| {
                    s.spawn(move || {
                        let r = end.rank() as u8;
                        // Rounds of different lengths, the sums between them.
                        let mut rounds = Vec::new();
                        for round in 0..4_u8 {
                            rounds.push(end.all_gather(vec![r; usize::from(round + r)]).unwrap());
                            assert_eq!(end.sum(&[u64::from(r), 1]).unwrap(), [3, 3]);
                        }
                        rounds
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for rounds in &gathered {
            for (round, parts) in rounds.iter().enumerate() {
                let expected: Vec<Vec<u8>> =
                    (0..3_u8).map(|r| vec![r; round + usize::from(r)]).collect();
                assert_eq!(parts, &expected);
            }
        }
    }
}
