//! Messages between ranks and the transport that carries them.
//!
//! The pitching protocol ([`crate::pitching`]) needs three messages: a vertex's new front time
//! after a tent ([`Update`], with a generation number so that a late arrival never overwrites a
//! newer one), "I am done" with the count of messages sent before it ([`Message::Done`], so that
//! termination needs no ordering between messages), and "stop, I failed"
//! ([`Message::Abort`]). A [`Transport`] sends them without blocking and receives them with a
//! timeout. [`loopback::Loopback`] carries them between threads of one process, with seeded random
//! delays; `mpi::MpiTransport` (with the cargo feature `mpi`) carries them between MPI
//! processes as [`Message::encode`]'s bytes, through one communication thread per process.

pub mod loopback;
#[cfg(feature = "mpi")]
pub mod mpi;

use std::time::Duration;

use sdg_mesh::VertexId;

use crate::partition::Rank;

/// A vertex's front time after a tent at it, sent by its owner to the ranks that hold it as a
/// ghost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Update {
    /// Global vertex id.
    pub vertex: VertexId,
    /// The vertex's new front time, seconds.
    pub time: f64,
    /// Tents pitched at the vertex so far: a receiver applies the update only if this is more
    /// than the generation of its copy.
    pub generation: u32,
}

/// What ranks tell each other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    /// A vertex moved.
    Update(Update),
    /// The sender owns no vertex below the end time any more and sent the receiver `sent`
    /// messages before this one; the receiver has them all once it has received that many.
    Done {
        /// Messages sent to the receiver before this one.
        sent: u64,
    },
    /// The sender failed; the receiver stops too.
    Abort,
}

/// Bytes of an encoded [`Message::Update`].
pub const UPDATE_BYTES: usize = 17;

/// Why a transport failed.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TransportError {
    #[error("no rank {to}: there are {ranks} ranks")]
    NoSuchRank { to: Rank, ranks: usize },
    #[error("a message of {len} bytes starting with kind {kind} is not a valid message")]
    Malformed { kind: u8, len: usize },
    #[error("the transport's communication thread has ended")]
    Closed,
}

/// Carries [`Message`]s between the ranks of one run. One value per rank; sends never wait for
/// the receiver.
pub trait Transport: Send {
    /// This rank.
    fn rank(&self) -> Rank;

    /// Number of ranks.
    fn ranks(&self) -> usize;

    /// Sends `message` to rank `to` (another rank) and returns without waiting for it to arrive.
    fn send(&mut self, to: Rank, message: Message) -> Result<(), TransportError>;

    /// The next message that arrived for this rank and its sender, waiting up to `timeout` for
    /// one (blocked, not spinning; zero only polls); `None` when none arrived in time.
    fn receive(&mut self, timeout: Duration) -> Result<Option<(Rank, Message)>, TransportError>;

    /// True when messages from one sender to one receiver arrive in the order they were sent
    /// (MPI's non-overtaking rule). The pitching protocol does not need it.
    fn is_fifo(&self) -> bool;
}

impl Message {
    /// Appends the message's bytes (little endian) to `out`: kind 0, vertex, generation and
    /// time bits for an update ([`UPDATE_BYTES`]); kind 1 and the count for done; kind 2 for
    /// abort.
    pub fn encode(&self, out: &mut Vec<u8>) {
        match *self {
            Message::Update(u) => {
                out.push(0);
                out.extend(u.vertex.to_le_bytes());
                out.extend(u.generation.to_le_bytes());
                out.extend(u.time.to_bits().to_le_bytes());
            }
            Message::Done { sent } => {
                out.push(1);
                out.extend(sent.to_le_bytes());
            }
            Message::Abort => out.push(2),
        }
    }

    /// The message [`Message::encode`] wrote into `bytes` (exactly one message).
    pub fn decode(bytes: &[u8]) -> Result<Self, TransportError> {
        let kind = bytes.first().copied().unwrap_or(u8::MAX);
        let malformed = TransportError::Malformed {
            kind,
            len: bytes.len(),
        };
        let word = |at: usize| -> [u8; 4] { bytes[at..at + 4].try_into().expect("4 bytes") };
        let long = |at: usize| -> [u8; 8] { bytes[at..at + 8].try_into().expect("8 bytes") };
        match (kind, bytes.len()) {
            (0, UPDATE_BYTES) => Ok(Message::Update(Update {
                vertex: u32::from_le_bytes(word(1)),
                generation: u32::from_le_bytes(word(5)),
                time: f64::from_bits(u64::from_le_bytes(long(9))),
            })),
            (1, 9) => Ok(Message::Done {
                sent: u64::from_le_bytes(long(1)),
            }),
            (2, 1) => Ok(Message::Abort),
            _ => Err(malformed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_survive_encoding_bitwise() {
        let messages = [
            Message::Update(Update {
                vertex: 70_000,
                time: 0.1 + 0.2,
                generation: 9,
            }),
            Message::Done { sent: 1 << 40 },
            Message::Abort,
        ];
        let mut bytes = Vec::new();
        for m in messages {
            bytes.clear();
            m.encode(&mut bytes);
            assert_eq!(Message::decode(&bytes), Ok(m));
        }
        assert_eq!(bytes.len(), 1);
        let mut update = Vec::new();
        messages[0].encode(&mut update);
        assert_eq!(update.len(), UPDATE_BYTES);
        assert_eq!(
            Message::decode(&update[..16]),
            Err(TransportError::Malformed { kind: 0, len: 16 })
        );
        assert!(Message::decode(&[]).is_err());
        assert!(Message::decode(&[3]).is_err());
    }
}
