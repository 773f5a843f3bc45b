//! A progress bar on a terminal: mean front time over end time, patches per second and ETA.
//! Silent when stderr is not a terminal or with `--quiet`.

use std::io::{IsTerminal, Write};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

/// Bar resolution: positions per run.
const STEPS: u64 = 1000;

/// Progress of a run measured in vertex-seconds of front advance.
#[derive(Debug)]
pub struct Progress {
    bar: Option<ProgressBar>,
    done: f64,
    total: f64,
    position: u64,
    start: Instant,
}

/// No bar: what a restored run has until [`Progress::new`] replaces it.
impl Default for Progress {
    fn default() -> Self {
        Self::new(false, 1.0)
    }
}

impl Progress {
    /// A bar for a run of `total` vertex-seconds (vertices times end time), shown when `enabled`
    /// and stderr is a terminal.
    pub fn new(enabled: bool, total: f64) -> Self {
        let bar = (enabled && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(STEPS);
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:40} {percent:>3}% of end time  {msg}  ETA {eta}",
                )
                .expect("valid template"),
            );
            bar
        });
        Self {
            bar,
            done: 0.0,
            total,
            position: 0,
            start: Instant::now(),
        }
    }

    /// Adds `dt` vertex-seconds of front advance after `patches` patches in all.
    pub fn advance(&mut self, dt: f64, patches: u64) {
        self.done += dt;
        let Some(bar) = &self.bar else { return };
        let position = ((self.done / self.total) * STEPS as f64) as u64;
        if position > self.position {
            self.position = position;
            let rate = patches as f64 / self.start.elapsed().as_secs_f64().max(1e-9);
            bar.set_message(format!("{rate:.0} patches/s"));
            bar.set_position(position);
        }
    }

    /// Adds `extra` vertex-seconds to the total (vertices added by refinement).
    pub fn grow(&mut self, extra: f64) {
        self.total += extra;
    }

    /// Clears the bar.
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

/// Writes `line` and a newline to stderr, or drops it if stderr cannot be written (a closed or
/// broken pipe, a terminal gone away), where `eprintln!` would panic: a message is never worth
/// a run.
pub fn note(line: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr(), "{line}");
}
