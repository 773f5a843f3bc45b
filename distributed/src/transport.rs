//! Messages between ranks and the transport that carries them.
//!
//! The pitching protocol ([`crate::pitching`]) needs four messages: a vertex's new front time
//! after a tent ([`Update`], with a generation number so that a late arrival never overwrites a
//! newer one, and when patches are solved the elements the tent left under the receiver's
//! triangles of its star, [`Cells`], each with a generation of its own), "I am done" with the
//! count of messages sent before it ([`Message::Done`], so that termination needs no ordering
//! between messages), "stop, I failed" ([`Message::Abort`]) and "pause for a checkpoint"
//! ([`Message::Pause`]). A [`Transport`] sends them without blocking, receives them with a
//! timeout, and sums values over the ranks at a barrier ([`Transport::sum`]).
//! [`loopback::Loopback`] carries them between threads of one process, with seeded random
//! delays; `mpi::MpiTransport` (with the cargo feature `mpi`) carries them between MPI
//! processes as [`Message::encode`]'s bytes, through one communication thread per process.

pub mod loopback;
#[cfg(feature = "mpi")]
pub mod mpi;

use std::time::Duration;

use sdg_mesh::VertexId;

use crate::partition::Rank;

/// A vertex's front time after a tent at it, sent by its owner to the ranks that hold it as a
/// ghost, with the elements under the vertex's star and the interface faces over its spokes
/// that the receiver holds, when patches are solved.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Update {
    /// Global vertex id.
    pub vertex: VertexId,
    /// The vertex's new front time, seconds.
    pub time: f64,
    /// Tents pitched at the vertex so far: a receiver applies the update only if this is more
    /// than the generation of its copy.
    pub generation: u32,
    /// The elements the tent left under the receiver's triangles of the star, keyed by global
    /// triangle (none when only pitching).
    pub elements: Cells,
    /// The interface faces the tent left over the receiver's edges among the spokes, keyed by
    /// global edge (none without interface laws).
    pub faces: Cells,
    /// When patches are solved, the entries of the sender's [`crate::held::Held::known`] that
    /// changed since its last update to the receiver: `(rank, value)`.
    pub work: Vec<(Rank, f64)>,
}

/// Elements under front triangles, or interface faces over front edges, as plain values
/// (bit-exact), each with its global triangle or edge id and its generation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cells {
    /// Per cell, its global id and generation (tents at the triangle's corners or the edge's
    /// ends so far): a receiver stores the cell only if this is more than its copy's.
    pub ids: Vec<(u32, u32)>,
    /// The cells' values back to back, `values.len() / ids.len()` each.
    pub values: Vec<f64>,
}

impl Cells {
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True without cells.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Values per cell (0 without cells).
    pub fn stride(&self) -> usize {
        self.values.len().checked_div(self.len()).unwrap_or(0)
    }

    /// Cell `i`: its global id, generation and values.
    pub fn get(&self, i: usize) -> (u32, u32, &[f64]) {
        let stride = self.stride();
        let (id, generation) = self.ids[i];
        (id, generation, &self.values[i * stride..(i + 1) * stride])
    }

    /// Bytes of the cells in [`Message::encode`]: 8 per cell and 8 per value.
    fn encoded_len(&self) -> usize {
        8 * (self.len() + self.values.len())
    }

    fn encode(&self, out: &mut Vec<u8>) {
        for &(id, generation) in &self.ids {
            out.extend(id.to_le_bytes());
            out.extend(generation.to_le_bytes());
        }
        for x in &self.values {
            out.extend(x.to_bits().to_le_bytes());
        }
    }

    /// `count` cells of `stride` values from the start of `bytes`, and the bytes after them.
    fn decode(bytes: &[u8], count: usize, stride: usize) -> Option<(Self, &[u8])> {
        let values = count.checked_mul(stride)?;
        let len = count.checked_add(values)?.checked_mul(8)?;
        if len > bytes.len() {
            return None;
        }
        let (cells, rest) = bytes.split_at(len);
        let word = |at: usize| u32::from_le_bytes(cells[at..at + 4].try_into().expect("4 bytes"));
        let ids = (0..count).map(|i| (word(8 * i), word(8 * i + 4))).collect();
        let values = cells[8 * count..]
            .chunks_exact(8)
            .map(|b| f64::from_bits(u64::from_le_bytes(b.try_into().expect("8 bytes"))))
            .collect();
        Some((Self { ids, values }, rest))
    }
}

/// What ranks tell each other.
#[derive(Clone, Debug, PartialEq)]
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
    /// The sender stops pitching for a checkpoint ([`crate::pitching::Pause`]); the receiver
    /// stops too and tells its own neighbour ranks. Counted like an update in
    /// [`Message::Done`]'s `sent`.
    Pause,
}

/// Bytes of an encoded [`Message::Update`] without cells or work entries; each cell adds 8
/// bytes and 8 per value, each work entry 12.
pub const UPDATE_BYTES: usize = 37;

/// Why a transport failed.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
pub enum TransportError {
    #[error("no rank {to}: there are {ranks} ranks")]
    NoSuchRank { to: Rank, ranks: usize },
    #[error("a message of {len} bytes starting with kind {kind} is not a valid message")]
    Malformed { kind: u8, len: usize },
    #[error("the transport's communication thread has ended")]
    Closed,
    #[error("rank {by} failed")]
    Aborted { by: Rank },
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

    /// Element-wise sums of `values` over all ranks, once every rank has called it (a
    /// barrier), after every message this rank sent before. Collective: every rank calls it
    /// with as many values. Messages arriving meanwhile wait for the next [`Self::receive`].
    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError>;

    /// What every rank gave as `bytes`, by rank, once every rank has called it (a barrier),
    /// after every message this rank sent before. Collective, like [`Self::sum`].
    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError>;
}

impl Update {
    /// Bytes of the update as [`Message::encode`] writes it.
    pub fn encoded_len(&self) -> usize {
        UPDATE_BYTES + self.elements.encoded_len() + self.faces.encoded_len() + 12 * self.work.len()
    }
}

impl Message {
    /// Appends the message's bytes (little endian) to `out`: for an update kind 0, vertex,
    /// generation, time bits, then count and values per cell of the elements and of the faces,
    /// and the count of work entries ([`UPDATE_BYTES`]), then per element its triangle and
    /// generation and the elements' values' bits, then the same for the faces, then per work
    /// entry its rank and value bits; kind 1 and the count for done; kind 2 for abort; kind 3
    /// for pause.
    pub fn encode(&self, out: &mut Vec<u8>) {
        match self {
            Message::Update(u) => {
                out.reserve(u.encoded_len());
                out.push(0);
                out.extend(u.vertex.to_le_bytes());
                out.extend(u.generation.to_le_bytes());
                out.extend(u.time.to_bits().to_le_bytes());
                for cells in [&u.elements, &u.faces] {
                    out.extend((cells.len() as u32).to_le_bytes());
                    out.extend((cells.stride() as u32).to_le_bytes());
                }
                out.extend((u.work.len() as u32).to_le_bytes());
                u.elements.encode(out);
                u.faces.encode(out);
                for &(rank, value) in &u.work {
                    out.extend(rank.to_le_bytes());
                    out.extend(value.to_bits().to_le_bytes());
                }
            }
            Message::Done { sent } => {
                out.push(1);
                out.extend(sent.to_le_bytes());
            }
            Message::Abort => out.push(2),
            Message::Pause => out.push(3),
        }
    }

    /// The message [`Message::encode`] wrote into `bytes` (exactly one message).
    pub fn decode(bytes: &[u8]) -> Result<Self, TransportError> {
        let kind = bytes.first().copied().unwrap_or(u8::MAX);
        let malformed = TransportError::Malformed {
            kind,
            len: bytes.len(),
        };
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
        let long = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        match (kind, bytes.len()) {
            (0, len) if len >= UPDATE_BYTES => {
                let size = |at: usize| word(at) as usize;
                let rest = &bytes[UPDATE_BYTES..];
                let (elements, rest) =
                    Cells::decode(rest, size(17), size(21)).ok_or(malformed.clone())?;
                let (faces, rest) =
                    Cells::decode(rest, size(25), size(29)).ok_or(malformed.clone())?;
                if size(33).checked_mul(12) != Some(rest.len()) {
                    return Err(malformed);
                }
                let work = rest
                    .chunks_exact(12)
                    .map(|b| {
                        let rank = Rank::from_le_bytes(b[..4].try_into().expect("4 bytes"));
                        let bits = u64::from_le_bytes(b[4..].try_into().expect("8 bytes"));
                        (rank, f64::from_bits(bits))
                    })
                    .collect();
                Ok(Message::Update(Update {
                    vertex: word(1),
                    generation: word(5),
                    time: f64::from_bits(long(9)),
                    elements,
                    faces,
                    work,
                }))
            }
            (1, 9) => Ok(Message::Done { sent: long(1) }),
            (2, 1) => Ok(Message::Abort),
            (3, 1) => Ok(Message::Pause),
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
                ..Update::default()
            }),
            Message::Update(Update {
                vertex: 3,
                time: 1e-300,
                generation: 1,
                elements: Cells {
                    ids: vec![(5, 2), (1 << 30, 7)],
                    values: vec![0.1, -0.0, f64::MIN_POSITIVE, 1.0 / 3.0, 2.5, -7e10],
                },
                faces: Cells {
                    ids: vec![(9, 4)],
                    values: vec![-1.5, 0.25],
                },
                work: vec![(2, 0.125), (0, -0.0)],
            }),
            Message::Done { sent: 1 << 40 },
            Message::Abort,
            Message::Pause,
        ];
        let mut bytes = Vec::new();
        for m in &messages {
            bytes.clear();
            m.encode(&mut bytes);
            if let Message::Update(u) = m {
                assert_eq!(bytes.len(), u.encoded_len());
            }
            let back = Message::decode(&bytes).unwrap();
            assert_eq!(&back, m);
            if let (Message::Update(a), Message::Update(b)) = (&back, m) {
                let bits = |u: &Update| {
                    (u.elements.values.iter().chain(&u.faces.values))
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>()
                };
                assert_eq!(bits(a), bits(b), "-0.0 stays -0.0");
            }
        }
        assert_eq!(bytes.len(), 1);
        let mut update = Vec::new();
        messages[0].encode(&mut update);
        assert_eq!(update.len(), UPDATE_BYTES);
        assert_eq!(
            Message::decode(&update[..16]),
            Err(TransportError::Malformed { kind: 0, len: 16 })
        );
        let mut cells = Vec::new();
        messages[1].encode(&mut cells);
        assert_eq!(
            cells.len(),
            UPDATE_BYTES + 8 * (2 + 6) + 8 * (1 + 2) + 12 * 2
        );
        let len = cells.len() - 8;
        assert_eq!(
            Message::decode(&cells[..len]),
            Err(TransportError::Malformed { kind: 0, len })
        );
        assert!(Message::decode(&[]).is_err());
        assert!(Message::decode(&[4]).is_err());
    }
}
