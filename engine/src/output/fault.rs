//! Faults injected into file writes, for the tests of a run's disk faults (`tests/disk.rs`,
//! `tests/chaos.rs`): the environment variable `SDG_FAULT`, read when a file is written (never
//! in the solving loop), makes the write of the files it names fail or pause as a real disk
//! would.
//!
//! `SDG_FAULT=KIND:NAME`, NAME a file name (`checkpoint_000002.sdgc`, `history.csv`) or a prefix
//! ending in `*` (`snapshot_*`), KIND one of
//! - `disk-full`: half the file is written to its temporary file, then the write fails with
//!   ENOSPC ("No space left on device");
//! - `read-only`: creating the temporary file fails with EROFS ("Read-only file system");
//! - `slow-write`: half the file is written, then the write waits [`SLOW`] and goes on (a
//!   signal during a checkpoint write).
//!
//! Any other value (e.g. `signal-listener`, a fault of the binary) injects nothing here.

use std::time::Duration;

/// The environment variable.
pub(crate) const VARIABLE: &str = "SDG_FAULT";

/// How long `slow-write` pauses a write.
pub(crate) const SLOW: Duration = Duration::from_secs(2);

/// ENOSPC and EROFS on Linux.
const NO_SPACE: i32 = 28;
const READ_ONLY: i32 = 30;

/// What happens to the write of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Fault {
    /// Fails with ENOSPC halfway.
    DiskFull,
    /// Fails with EROFS when the temporary file is created.
    ReadOnly,
    /// Pauses [`SLOW`] halfway.
    Slow,
}

impl Fault {
    /// The fault `SDG_FAULT` injects into the write of the file `name`, if any.
    pub(crate) fn injected(name: &str) -> Option<Self> {
        Self::parse(&std::env::var(VARIABLE).ok()?, name)
    }

    /// The fault `spec` (the value of `SDG_FAULT`) injects into the write of `name`.
    fn parse(spec: &str, name: &str) -> Option<Self> {
        let (kind, pattern) = spec.split_once(':')?;
        let fault = match kind {
            "disk-full" => Self::DiskFull,
            "read-only" => Self::ReadOnly,
            "slow-write" => Self::Slow,
            _ => return None,
        };
        let matches = match pattern.strip_suffix('*') {
            Some(prefix) => name.starts_with(prefix),
            None => name == pattern,
        };
        matches.then_some(fault)
    }

    /// Before the temporary file is created.
    pub(crate) fn at_create(self) -> std::io::Result<()> {
        match self {
            Self::ReadOnly => Err(std::io::Error::from_raw_os_error(READ_ONLY)),
            Self::DiskFull | Self::Slow => Ok(()),
        }
    }

    /// Halfway through the write.
    pub(crate) fn halfway(self) -> std::io::Result<()> {
        match self {
            Self::DiskFull => Err(std::io::Error::from_raw_os_error(NO_SPACE)),
            Self::Slow => {
                std::thread::sleep(SLOW);
                Ok(())
            }
            Self::ReadOnly => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fault_applies_to_the_files_it_names() {
        let full = "disk-full:checkpoint_000002.sdgc";
        assert_eq!(
            Fault::parse(full, "checkpoint_000002.sdgc"),
            Some(Fault::DiskFull)
        );
        assert_eq!(Fault::parse(full, "checkpoint_000001.sdgc"), None);
        let snapshots = "read-only:snapshot_*";
        assert_eq!(
            Fault::parse(snapshots, "snapshot_0003.vtu"),
            Some(Fault::ReadOnly)
        );
        assert_eq!(Fault::parse(snapshots, "snapshots.pvd"), None);
        assert_eq!(Fault::parse(snapshots, "history.csv"), None);
        assert_eq!(Fault::parse("slow-write:*", "a.csv"), Some(Fault::Slow));
        assert_eq!(Fault::parse("signal-listener", "a.csv"), None);
        assert_eq!(Fault::parse("gone:a.csv", "a.csv"), None);
    }

    #[test]
    fn the_injected_errors_are_those_of_a_full_or_read_only_disk() {
        let full = Fault::DiskFull.halfway().unwrap_err();
        assert_eq!(full.kind(), std::io::ErrorKind::StorageFull);
        assert!(Fault::DiskFull.at_create().is_ok());
        let read_only = Fault::ReadOnly.at_create().unwrap_err();
        assert_eq!(read_only.kind(), std::io::ErrorKind::ReadOnlyFilesystem);
    }
}
