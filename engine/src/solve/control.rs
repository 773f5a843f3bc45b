//! Requests to a running solve from outside its workers: signals, job control, the wall-time
//! limit and failed guards.

use std::sync::atomic::{AtomicBool, Ordering};

use parking_lot::Mutex;

/// Requests to a running solve from outside its workers (signals, job control): it pauses at
/// the next quiescent point, writes a checkpoint and goes on, or stops with exit code 3.
#[derive(Debug, Default)]
pub struct Control {
    pending: AtomicBool,
    request: Mutex<Request>,
}

/// What was asked since the last checkpoint.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Request {
    /// Write a checkpoint and go on.
    pub(crate) checkpoint: bool,
    /// Write a checkpoint and stop, for this reason.
    pub(crate) stop: Option<String>,
    /// Write a checkpoint and fail (exit code 1): a patch failed a guard.
    pub(crate) failure: Option<String>,
}

impl Request {
    /// Adds what `other` asks: a checkpoint, and a stop or failure reason where this has none.
    pub(crate) fn merge(&mut self, other: Request) {
        self.checkpoint |= other.checkpoint;
        if self.stop.is_none() {
            self.stop = other.stop;
        }
        if self.failure.is_none() {
            self.failure = other.failure;
        }
    }

    /// True when anything is asked.
    pub(crate) fn any(&self) -> bool {
        self.checkpoint || self.stop.is_some() || self.failure.is_some()
    }
}

impl Control {
    /// Asks for a checkpoint, after which the run goes on (SIGUSR1).
    pub fn checkpoint(&self) {
        self.request.lock().checkpoint = true;
        self.pending.store(true, Ordering::Release);
    }

    /// Asks for a checkpoint and a stop with exit code 3 (SIGTERM, SIGINT, SIGHUP, the wall-time
    /// limit); `reason` says why. The first reason given is kept.
    pub fn stop(&self, reason: impl Into<String>) {
        self.request
            .lock()
            .stop
            .get_or_insert_with(|| reason.into());
        self.pending.store(true, Ordering::Release);
    }

    /// Asks for a checkpoint and a failure (exit code 1) with `reason`: a patch failed a
    /// guard and was not stored. The first reason given is kept.
    pub(crate) fn fail(&self, reason: String) {
        self.request.lock().failure.get_or_insert(reason);
        self.pending.store(true, Ordering::Release);
    }

    /// True when a request waits.
    pub(crate) fn is_pending(&self) -> bool {
        self.pending.load(Ordering::Acquire)
    }

    /// Takes the requests.
    pub(crate) fn take(&self) -> Request {
        let mut request = self.request.lock();
        self.pending.store(false, Ordering::Release);
        std::mem::take(&mut *request)
    }
}
