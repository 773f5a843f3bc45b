//! Signals of `sdg run` and `sdg study`: requests to checkpoint and stop, heard by a thread of
//! their own.

use std::sync::Arc;

use sdg_engine::study::Stop;
use sdg_engine::{Control, EngineError};

/// What a signal asks of the process that hears it.
pub(crate) trait Requests: Send + Sync + 'static {
    /// SIGTERM, SIGINT or SIGHUP (`name`): checkpoint and stop; returns what to tell the user.
    fn stop(&self, name: &str) -> String;
    /// SIGUSR1: a checkpoint, and go on.
    fn checkpoint(&self);
}

impl Requests for Control {
    fn stop(&self, name: &str) -> String {
        Control::stop(self, format!("{name} received"));
        format!("{name}: writing a checkpoint, then stopping (again to exit at once)")
    }

    fn checkpoint(&self) {
        Control::checkpoint(self);
        aside(|| tracing::info!("SIGUSR1: a checkpoint at the next quiescent point"));
    }
}

impl Requests for Stop {
    fn stop(&self, name: &str) -> String {
        self.request();
        format!(
            "{name}: the running cases write a checkpoint and stop, no other case starts; run \
             the study again to go on (again to exit at once)"
        )
    }

    fn checkpoint(&self) {
        Stop::checkpoint(self);
    }
}

/// A second SIGTERM or SIGINT within this long of the first is taken as the same request.
const SAME_REQUEST: std::time::Duration = std::time::Duration::from_secs(1);

/// The environment variable that injects a fault for the tests (`tests/faults.rs`):
/// `signal-listener` makes the signal listener panic when SIGUSR1 arrives. (The engine reads
/// it too, for faults of file writes: `engine/src/output/fault.rs`.)
const FAULT: &str = "SDG_FAULT";

/// Turns signals into requests to the run (or the study's runs): SIGTERM, SIGINT and SIGHUP
/// (the terminal or the job's session gone) checkpoint and stop (exit 3), SIGUSR1 checkpoints
/// and goes on. A second
/// SIGTERM, SIGINT or SIGHUP, [`SAME_REQUEST`] or more after the first, ends the process at
/// once with code 130, without waiting for the checkpoint (the one before it is left whole).
/// Started first thing in `sdg run`, so that a signal during set-up stops the run the same
/// way, with a checkpoint of the initial state.
///
/// Once listening, the process no longer dies of these signals: should the listener end, the
/// run would go on deaf to them. Nothing in it may panic on output (its messages are dropped if
/// stderr cannot be written), and should it panic all the same (a bug) the process exits at once
/// with code 1, as after SIGKILL (files are written whole or not at all).
pub(crate) fn listen_to_signals(control: Arc<impl Requests>) -> Result<(), EngineError> {
    use tokio::signal::unix::{SignalKind, signal};
    let failed = |e: std::io::Error| EngineError::Runtime(format!("signal handling: {e}"));
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .build()
        .map_err(failed)?;
    let listen = |kind| {
        let _guard = runtime.enter();
        signal(kind).map_err(failed)
    };
    let (mut term, mut int, mut hup, mut usr1) = (
        listen(SignalKind::terminate())?,
        listen(SignalKind::interrupt())?,
        listen(SignalKind::hangup())?,
        listen(SignalKind::user_defined1())?,
    );
    let fault = std::env::var_os(FAULT).is_some_and(|f| f == "signal-listener");
    let listener = async move {
        let mut stopping: Option<std::time::Instant> = None;
        loop {
            let name = tokio::select! {
                _ = term.recv() => "SIGTERM",
                _ = int.recv() => "SIGINT",
                _ = hup.recv() => "SIGHUP",
                _ = usr1.recv() => {
                    if fault {
                        panic!("{FAULT}=signal-listener: a panic on SIGUSR1");
                    }
                    control.checkpoint();
                    continue;
                }
            };
            if let Some(first) = stopping {
                // A batch system may signal both the job's shell and sdg, and the shell
                // pass its signal on: one within a second is the same request.
                if first.elapsed() < SAME_REQUEST {
                    continue;
                }
                let said = aside(move || {
                    note!("{name} again: exiting without waiting for the checkpoint");
                });
                let _ = said.recv_timeout(std::time::Duration::from_millis(100));
                std::process::exit(130);
            }
            stopping = Some(std::time::Instant::now());
            let message = control.stop(name);
            aside(move || note!("{message}"));
        }
    };
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let listening = std::panic::AssertUnwindSafe(|| runtime.block_on(listener));
            if std::panic::catch_unwind(listening).is_err() {
                note!(
                    "error: internal error: the signal listener failed (a bug, please report \
                     it with the message above); exiting without a checkpoint"
                );
                std::process::exit(1);
            }
        })
        .map_err(failed)?;
    Ok(())
}

/// Runs `write` on a thread of its own, so that the signal listener never waits for stderr (a
/// pipe nobody reads, a terminal stopped by Ctrl-S): the receiver hears when it is done, or
/// is disconnected if the thread could not start.
fn aside(write: impl FnOnce() + Send + 'static) -> std::sync::mpsc::Receiver<()> {
    let (done, said) = std::sync::mpsc::channel();
    let _ = std::thread::Builder::new()
        .name("signal message".into())
        .spawn(move || {
            write();
            let _ = done.send(());
        });
    said
}
