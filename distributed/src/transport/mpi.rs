//! The MPI transport: ranks are MPI processes, and one communication thread per process makes
//! every MPI call.
//!
//! # Threads
//! [`MpiTransport::start`] spawns the communication thread, which initialises MPI with
//! `MPI_THREAD_FUNNELED` (the process may have many threads, only the one that initialised MPI
//! calls it), makes every MPI call of the process and finalises MPI when the transport is
//! dropped. Funneled is the least level that allows the workers' threads at all, and the only
//! one this design needs: the workers never touch MPI, they hand outgoing messages to the
//! thread through a channel and take incoming ones from another channel ([`Transport::send`]
//! never blocks, [`Transport::receive`] waits on the channel, never spins). MPI belongs to the
//! transport: one per process, and nothing else in the process may initialise MPI.
//!
//! # Messages
//! Each [`Message`] travels as its [`Message::encode`] bytes in one MPI message of tag
//! [`TAG`] on a duplicate of `MPI_COMM_WORLD`, so that other MPI traffic cannot match it. One
//! thread posts the sends in the order the workers made them and MPI does not let messages of
//! one sender overtake each other on one communicator and tag, so the transport is FIFO per
//! pair of ranks.
//!
//! # Waiting without spinning
//! MPI has no blocking wait for "a message arrived or a worker wants to send". The thread
//! therefore takes all pending incoming messages (`MPI_Improbe` and a matched receive until
//! none is left), posts the workers' messages (`MPI_Isend`), and when neither had anything to
//! do sleeps on the workers' channel with a timeout that doubles from
//! [`MpiOptions::min_poll`] to [`MpiOptions::max_poll`] while the worker waits for a message,
//! and to [`MpiOptions::busy_poll`] while it works. A worker's message wakes it at once, so
//! outgoing messages leave without delay, and so does a worker that starts waiting; an
//! incoming message is noticed within `max_poll` while the worker waits for one, and within
//! `busy_poll` while it has other tents to pitch. A blocking `MPI_Probe` would miss the
//! workers' messages, and `MPI_Iprobe` in a loop would spin a core that the workers need (3
//! and 4 ranks run on 2 cores in CI). Nor may the thread wake often while the worker works:
//! at the 100 us of `max_poll` throughout, a rank of `plane_wave` alone (`mpirun -n 1`) solved
//! its patches 20% slower than a run without MPI.
//!
//! # Sends that wait for their receiver
//! The sends of one round are posted together and the thread goes on receiving (and sleeping
//! briefly between tests) until every one has completed, so two ranks sending to each other
//! cannot deadlock even when MPI completes a send only once it is matched. The small messages
//! of the protocol normally complete at once (eager protocol).
//!
//! # Shutdown
//! Dropping the transport ends the thread after it has sent everything the worker handed it;
//! the thread then finalises MPI, which waits for the other processes. [`MpiTransport::abort`]
//! ends every process of the run with `MPI_Abort`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::Duration;

use ::mpi::Threading;
use ::mpi::collective::SystemOperation;
use ::mpi::datatype::PartitionMut;
use ::mpi::point_to_point::MatchedReceiveVec;
use ::mpi::request::{Request, scope};
use ::mpi::topology::SimpleCommunicator;
use ::mpi::traits::{Communicator, CommunicatorCollectives, Destination, Source};

use super::{Message, Transport, TransportError};
use crate::partition::Rank;

/// Tag of the transport's MPI messages.
pub const TAG: ::mpi::Tag = 68;

/// How the communication thread waits when it has nothing to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MpiOptions {
    /// First sleep after the last activity.
    pub min_poll: Duration,
    /// Longest sleep while the worker waits for a message: it is noticed at most this late.
    pub max_poll: Duration,
    /// Longest sleep while the worker has tents to pitch (messages wait in MPI meanwhile).
    pub busy_poll: Duration,
}

impl Default for MpiOptions {
    /// 10 us doubling to 100 us while the worker waits: the thread wakes about 10,000 times a
    /// second, and a rank waiting for its neighbour's update loses at most about 0.1 ms (plus
    /// the kernel's timer slack, 50 us by default); to 2 ms while it works. Pitching alone (0.3 us a tent)
    /// is bound by that latency: on `examples/mpi_pitch.rs` with 2 ranks a cap of 500 us made
    /// the ranks wait 183 ms of 207 ms, 100 us 69 ms of 89 ms, 20 us 48 ms of 62 ms (the serial
    /// run takes 24 ms); with patch solves between updates it matters far less.
    fn default() -> Self {
        MpiOptions {
            min_poll: Duration::from_micros(10),
            max_poll: Duration::from_micros(100),
            busy_poll: Duration::from_millis(2),
        }
    }
}

/// Why the MPI transport could not start.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum MpiError {
    #[error("MPI was initialised already in this process: one MPI transport per process")]
    AlreadyInitialised,
    #[error(
        "the MPI library offers thread level {provided}, the transport needs MPI_THREAD_FUNNELED"
    )]
    Threading { provided: String },
    #[error("could not start the MPI communication thread: {0}")]
    Thread(String),
    #[error("the MPI communication thread ended while starting")]
    Ended,
}

/// What a worker asks the communication thread to do.
#[derive(Debug)]
enum Command {
    Send {
        to: Rank,
        message: Message,
    },
    Sum {
        values: Vec<u64>,
        reply: Sender<Vec<u64>>,
    },
    Gather {
        bytes: Vec<u8>,
        reply: Sender<Vec<Vec<u8>>>,
    },
    Abort {
        code: i32,
    },
    /// The worker started waiting for a message: poll at `max_poll` at most.
    Hurry,
}

/// An incoming message (or why its bytes were not one) and its sender.
type Incoming = (Rank, Result<Message, TransportError>);

/// This process's end of the MPI transport (see the module docs).
#[derive(Debug)]
pub struct MpiTransport {
    rank: Rank,
    ranks: usize,
    /// `None` once dropped: that ends the communication thread.
    commands: Option<Sender<Command>>,
    incoming: Receiver<Incoming>,
    /// Set while the worker waits in [`Transport::receive`].
    waiting: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl MpiTransport {
    /// Starts the communication thread, which initialises MPI (this process's rank and the
    /// number of ranks are `MPI_COMM_WORLD`'s).
    pub fn start(options: MpiOptions) -> Result<Self, MpiError> {
        let (commands, commands_rx) = mpsc::channel();
        let (incoming_tx, incoming) = mpsc::channel();
        let (ready_tx, ready) = mpsc::channel();
        let waiting = Arc::new(AtomicBool::new(false));
        let worker_waits = Arc::clone(&waiting);
        let thread = std::thread::Builder::new()
            .name("mpi".to_string())
            .spawn(move || {
                let channels = Channels {
                    commands: &commands_rx,
                    incoming: &incoming_tx,
                    worker_waits: &worker_waits,
                };
                communicate(options, &channels, &ready_tx)
            })
            .map_err(|e| MpiError::Thread(e.to_string()))?;
        match ready.recv() {
            Ok(Ok((rank, ranks))) => Ok(MpiTransport {
                rank,
                ranks,
                commands: Some(commands),
                incoming,
                waiting,
                thread: Some(thread),
            }),
            Ok(Err(e)) => {
                let _ = thread.join();
                Err(e)
            }
            Err(_) => {
                let _ = thread.join();
                Err(MpiError::Ended)
            }
        }
    }

    fn command(&self, command: Command) -> Result<(), TransportError> {
        self.commands
            .as_ref()
            .and_then(|c| c.send(command).ok())
            .ok_or(TransportError::Closed)
    }

    /// Ends every process of the run with exit code `code` (`MPI_Abort`), after the messages
    /// this rank sent before.
    pub fn abort(mut self, code: i32) -> ! {
        let _ = self.command(Command::Abort { code });
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        // Only reached when the communication thread had ended already.
        std::process::exit(code)
    }
}

impl Drop for MpiTransport {
    fn drop(&mut self) {
        self.commands = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Transport for MpiTransport {
    fn rank(&self) -> Rank {
        self.rank
    }

    fn ranks(&self) -> usize {
        self.ranks
    }

    fn send(&mut self, to: Rank, message: Message) -> Result<(), TransportError> {
        if to as usize >= self.ranks {
            return Err(TransportError::NoSuchRank {
                to,
                ranks: self.ranks,
            });
        }
        self.command(Command::Send { to, message })
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<(Rank, Message)>, TransportError> {
        let mut next = self.incoming.try_recv().map_err(|e| match e {
            TryRecvError::Empty => RecvTimeoutError::Timeout,
            TryRecvError::Disconnected => RecvTimeoutError::Disconnected,
        });
        if !timeout.is_zero() && matches!(next, Err(RecvTimeoutError::Timeout)) {
            self.waiting.store(true, Ordering::Relaxed);
            self.command(Command::Hurry)?;
            next = self.incoming.recv_timeout(timeout);
            self.waiting.store(false, Ordering::Relaxed);
        }
        match next {
            Ok((from, message)) => message.map(|m| Some((from, m))),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => Err(TransportError::Closed),
        }
    }

    fn is_fifo(&self) -> bool {
        true
    }

    /// `MPI_Allgatherv` on the communication thread, after the messages sent before.
    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError> {
        let (reply, gathered) = mpsc::channel();
        self.command(Command::Gather { bytes, reply })?;
        gathered.recv().map_err(|_| TransportError::Closed)
    }

    /// `MPI_Allreduce`: messages arriving meanwhile wait in MPI. A rank that never calls it
    /// (one that died) leaves the others waiting until `mpirun` ends them.
    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError> {
        let (reply, sums) = mpsc::channel();
        self.command(Command::Sum {
            values: values.to_vec(),
            reply,
        })?;
        sums.recv().map_err(|_| TransportError::Closed)
    }
}

/// The communication thread's ends of the channels to the worker.
struct Channels<'a> {
    commands: &'a Receiver<Command>,
    incoming: &'a Sender<Incoming>,
    /// Set while the worker waits for a message.
    worker_waits: &'a AtomicBool,
}

/// The communication thread: initialises MPI, says this rank and the number of ranks on
/// `ready`, then moves messages until the worker drops its end of `commands`, and finalises.
fn communicate(
    options: MpiOptions,
    channels: &Channels<'_>,
    ready: &Sender<Result<(Rank, usize), MpiError>>,
) {
    let Channels {
        commands, incoming, ..
    } = *channels;
    let Some((universe, provided)) = ::mpi::initialize_with_threading(Threading::Funneled) else {
        let _ = ready.send(Err(MpiError::AlreadyInitialised));
        return;
    };
    if matches!(provided, Threading::Single) {
        let _ = ready.send(Err(MpiError::Threading {
            provided: "MPI_THREAD_SINGLE".to_string(),
        }));
        return;
    }
    let world = universe.world().duplicate();
    let _ = ready.send(Ok((world.rank() as Rank, world.size() as usize)));
    let mut outgoing: Vec<(Rank, Vec<u8>)> = Vec::new();
    let mut pause = Duration::ZERO;
    loop {
        let mut active = false;
        let mut open = true;
        let mut next = commands.recv_timeout(pause);
        loop {
            match next {
                Ok(Command::Send { to, message }) => {
                    let mut bytes = Vec::with_capacity(super::UPDATE_BYTES);
                    message.encode(&mut bytes);
                    outgoing.push((to, bytes));
                }
                Ok(Command::Sum { values, reply }) => {
                    send_all(&world, &mut outgoing, incoming, options);
                    let mut sums = vec![0_u64; values.len()];
                    world.all_reduce_into(&values[..], &mut sums[..], SystemOperation::sum());
                    let _ = reply.send(sums);
                }
                Ok(Command::Gather { bytes, reply }) => {
                    send_all(&world, &mut outgoing, incoming, options);
                    let _ = reply.send(all_gather(&world, &bytes));
                }
                Ok(Command::Abort { code }) => {
                    send_all(&world, &mut outgoing, incoming, options);
                    world.abort(code);
                }
                Ok(Command::Hurry) => {}
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => {
                    open = false;
                    break;
                }
            }
            active = true;
            next = commands.try_recv().map_err(|e| match e {
                TryRecvError::Empty => RecvTimeoutError::Timeout,
                TryRecvError::Disconnected => RecvTimeoutError::Disconnected,
            });
        }
        active |= receive_all(&world, incoming) > 0;
        send_all(&world, &mut outgoing, incoming, options);
        if !open {
            break;
        }
        let longest = if channels.worker_waits.load(Ordering::Relaxed) {
            options.max_poll
        } else {
            options.busy_poll
        };
        pause = match (active, pause.is_zero()) {
            (true, _) => Duration::ZERO,
            (false, true) => options.min_poll,
            (false, false) => (pause * 2).min(longest),
        };
    }
    // The duplicate communicator is freed before MPI is finalised.
    drop(world);
    drop(universe);
}

/// What every rank gave as `bytes`, by rank (`MPI_Allgather` of the lengths, then
/// `MPI_Allgatherv`).
fn all_gather(world: &SimpleCommunicator, bytes: &[u8]) -> Vec<Vec<u8>> {
    let ranks = world.size() as usize;
    let length = i32::try_from(bytes.len()).expect("a gathered part below 2 GiB");
    let mut lengths = vec![0_i32; ranks];
    world.all_gather_into(&length, &mut lengths[..]);
    let starts: Vec<i32> = (lengths.iter())
        .scan(0_i32, |at, &l| {
            let start = *at;
            *at += l;
            Some(start)
        })
        .collect();
    let total: usize = lengths.iter().map(|&l| l as usize).sum();
    let mut all = vec![0_u8; total];
    {
        let mut parts = PartitionMut::new(&mut all[..], &lengths[..], &starts[..]);
        world.all_gather_varcount_into(bytes, &mut parts);
    }
    (starts.iter().zip(&lengths))
        .map(|(&s, &l)| all[s as usize..(s + l) as usize].to_vec())
        .collect()
}

/// Passes every message that has arrived to the worker; returns how many.
fn receive_all(world: &SimpleCommunicator, incoming: &Sender<Incoming>) -> usize {
    let mut count = 0;
    while let Some(probed) = world.any_process().immediate_matched_probe_with_tag(TAG) {
        let (bytes, status) = probed.matched_receive_vec::<u8>();
        // A worker that dropped its end stops reading; what it misses does not matter then.
        let _ = incoming.send((status.source_rank() as Rank, Message::decode(&bytes)));
        count += 1;
    }
    count
}

/// Posts every message in `outgoing` and receives until all have completed (see the module
/// docs for why it receives meanwhile), sleeping briefly between tests while nothing arrives.
fn send_all(
    world: &SimpleCommunicator,
    outgoing: &mut Vec<(Rank, Vec<u8>)>,
    incoming: &Sender<Incoming>,
    options: MpiOptions,
) {
    if outgoing.is_empty() {
        return;
    }
    scope(|scope| {
        let mut pending: Vec<Request<'_, [u8], _>> = outgoing
            .iter()
            .map(|(to, bytes)| {
                world
                    .process_at_rank(*to as ::mpi::Rank)
                    .immediate_send_with_tag(scope, &bytes[..], TAG)
            })
            .collect();
        let mut pause = Duration::ZERO;
        loop {
            pending = pending.into_iter().filter_map(|r| r.test().err()).collect();
            if pending.is_empty() {
                break;
            }
            if receive_all(world, incoming) > 0 {
                pause = Duration::ZERO;
            } else {
                std::thread::sleep(pause);
                pause = (pause * 2).clamp(options.min_poll, options.max_poll);
            }
        }
    });
    outgoing.clear();
}
