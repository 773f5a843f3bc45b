//! Checkpoints: the whole state of a solve at a quiescent point of the front (no tent in flight,
//! no event queued), so that `sdg run --restart` goes on exactly where the run stopped.
//!
//! A checkpoint holds the mesh, the front, the elements under it with the interface states, the
//! pitcher's budgets, the adaptivity flags, crack tips, the bookkeeping (energy accounts,
//! counters, history rows, pending snapshot slices, milestones, probe samples, crack crossings
//! and fracture events) and the configuration it ran. Random draws need no state: they are
//! keyed by the run seed and stable ids. Deterministic runs pause between rounds, so a resumed
//! run is bitwise the same as an uninterrupted one, on any number of threads.
//!
//! The file, `checkpoint_NNNNNN.sdgc`, is [`MAGIC`], the format version (u32), the payload's
//! length (u64) and CRC-32 (u32), all little-endian, then the payload: the state in CBOR
//! (RFC 8949: self-describing and the same on every machine, readable from Python's `cbor2`),
//! zlib-compressed. It is written to a temporary file, synced and renamed, so a reader sees a
//! whole checkpoint or none. A file with another magic, version, length or checksum, or written
//! by another configuration, is refused with the reason.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::book::Book;
use crate::config::Config;
use crate::error::EngineError;
use crate::frontier::Frontier;

/// The first bytes of every checkpoint file.
const MAGIC: &[u8; 8] = b"SDGCKPT\n";
/// The layout of the payload; a reader refuses any other.
const FORMAT: u32 = 2;
/// Bytes before the payload: magic, format, length, checksum.
const PREAMBLE: usize = 8 + 4 + 8 + 4;
/// zlib level: fast; the solution's floating-point bits compress little anyway.
const LEVEL: u8 = 1;
/// Configuration keys a restart may change: they do not enter the state.
const FREE_KEYS: [&str; 5] = [
    "scheduler",
    "limits",
    "checkpoint",
    "output.dir",
    "output.vtu",
];

/// Configuration keys a restart may change to extend the run (after the checkpoint's front).
const EXTENSION_KEYS: [&str; 2] = ["time.end", "output.snapshot_times"];

/// Counts of the run so far that live outside the bookkeeping.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub(crate) struct Counts {
    /// Tents, topology events and deterministic rounds so far.
    pub(crate) tents: u64,
    pub(crate) events: u64,
    pub(crate) rounds: u64,
    /// Wall time of the solve so far, s, over every restart.
    pub(crate) wall_time_s: f64,
    /// The scheduler's events and waiting so far, s, summed over threads.
    pub(crate) events_s: f64,
    pub(crate) waiting_s: f64,
    /// Checkpoints written so far: the number of the next file.
    pub(crate) written: u64,
}

/// What identifies a checkpoint without its state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Header {
    /// The `sdg` version that wrote it.
    pub(crate) version: String,
    /// The configuration of the run, as JSON.
    pub(crate) config: String,
    /// The front's least time, s.
    pub(crate) time: f64,
}

/// A checkpoint being written: borrowed from the running solve.
#[derive(Serialize)]
struct Saved<'a> {
    header: Header,
    counts: Counts,
    frontier: &'a Frontier,
    book: &'a Book,
}

/// A checkpoint read back.
#[derive(Deserialize)]
pub(crate) struct Restored {
    pub(crate) header: Header,
    pub(crate) counts: Counts,
    pub(crate) frontier: Frontier,
    pub(crate) book: Book,
}

/// The checkpoint folder of a run and how many files it keeps.
#[derive(Debug)]
pub(crate) struct Folder {
    pub(crate) dir: PathBuf,
    keep: usize,
}

impl Folder {
    /// The folder of `config` whose outputs go to `output`.
    pub(crate) fn new(config: &Config, output: &Path) -> Self {
        let c = &config.checkpoint;
        Self {
            dir: c.dir.clone().unwrap_or_else(|| output.join("checkpoints")),
            keep: c.keep.unwrap_or(2) as usize,
        }
    }

    /// Refuses (exit 2) to write into a folder that already holds checkpoints, unless the run
    /// restarts from that folder (`restart` is it or a file in it): a new run numbers its files
    /// from 1, so the rotation by number would keep the earlier run's files and delete its own,
    /// and `--restart` on the folder would pick up the earlier run.
    pub(crate) fn check_unmixed(&self, restart: Option<&Path>) -> Result<(), EngineError> {
        let existing = list(&self.dir);
        let Some(newest) = existing.last() else {
            return Ok(());
        };
        let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        let source = restart.and_then(|p| if p.is_dir() { Some(p) } else { p.parent() });
        if source.is_some_and(|s| same(s, &self.dir)) {
            return Ok(());
        }
        let name = newest.file_name().map_or_else(
            || newest.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Err(EngineError::Input(format!(
            "{}: holds {} checkpoint file(s) of an earlier run (the newest {name}); a run \
             would number its own from 0 beside them and keep theirs. Go on from them with \
             `--restart {}`, or move them away, or write elsewhere (`--output` or \
             `checkpoint.dir`)",
            self.dir.display(),
            existing.len(),
            self.dir.display()
        )))
    }

    /// The number of the next checkpoint file of a run restarted from one that recorded
    /// `written` files before it: after that one and after every file already in the folder,
    /// so that a restart never overwrites the checkpoint it started from, and the newest file
    /// (what `--restart` on the folder takes) is always the last one written.
    pub(crate) fn next_number(&self, written: u64) -> u64 {
        let numbered = list(&self.dir).into_iter().filter_map(|p| {
            p.file_stem()?
                .to_str()?
                .strip_prefix("checkpoint_")?
                .parse::<u64>()
                .ok()
        });
        numbered.map(|n| n + 1).fold(written + 1, u64::max)
    }

    /// The file name of checkpoint number `number`.
    fn name(number: u64) -> String {
        format!("checkpoint_{number:06}.sdgc")
    }

    /// Where checkpoint number `number` is written.
    pub(crate) fn path(&self, number: u64) -> PathBuf {
        self.dir.join(Self::name(number))
    }

    /// Writes checkpoint number `counts.written` of `frontier` and `book` (held still by the
    /// caller), then removes all but the newest `keep`. Returns its path.
    pub(crate) fn write(
        &self,
        config: &Config,
        counts: Counts,
        frontier: &Frontier,
        book: &Book,
    ) -> Result<PathBuf, EngineError> {
        let saved = Saved {
            header: Header {
                version: env!("CARGO_PKG_VERSION").into(),
                config: config_json(config),
                time: frontier.front.min_time(),
            },
            counts,
            frontier,
            book,
        };
        let mut cbor = Vec::new();
        ciborium::into_writer(&saved, &mut cbor)
            .map_err(|e| EngineError::Runtime(format!("checkpoint: encoding the state: {e}")))?;
        let payload = miniz_oxide::deflate::compress_to_vec_zlib(&cbor, LEVEL);
        drop(cbor);
        let mut bytes = Vec::with_capacity(PREAMBLE + payload.len());
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT.to_le_bytes());
        bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        bytes.extend_from_slice(&payload);
        let name = Self::name(counts.written);
        // Made here, not with its parents: an output folder removed under the job is an error.
        match std::fs::create_dir(&self.dir) {
            Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => {
                let (path, source) = (self.dir.clone(), e);
                return Err(EngineError::Write { path, source });
            }
            _ => {}
        }
        let path = crate::output::write_synced(&self.dir, &name, &bytes)?;
        let mut files = list(&self.dir);
        files.truncate(files.len().saturating_sub(self.keep));
        for old in files {
            if let Err(e) = std::fs::remove_file(&old) {
                tracing::warn!("{}: cannot remove an old checkpoint: {e}", old.display());
            }
        }
        Ok(path)
    }
}

/// Whether `dir` holds a checkpoint file (valid or not: a restart from the folder takes the
/// newest valid one, or says why there is none).
pub(crate) fn holds_checkpoint(dir: &Path) -> bool {
    !list(dir).is_empty()
}

/// The checkpoint files in `dir`, oldest first (by number).
fn list(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("checkpoint_") && n.ends_with(".sdgc"))
        })
        .collect();
    files.sort();
    files
}

/// The configuration as the checkpoint stores it.
fn config_json(config: &Config) -> String {
    serde_json::to_string(config).expect("the configuration serializes")
}

/// Reads the checkpoint at `path`, or the newest valid one when `path` is a folder, for a run
/// of `config`. A file that is not a whole checkpoint of this configuration is refused (exit 2)
/// with the reason; in a folder, older files are tried after a refused newer one.
pub(crate) fn restore(path: &Path, config: &Config) -> Result<(PathBuf, Restored), EngineError> {
    let refuse = |reason: String| EngineError::Input(reason);
    if !path.is_dir() {
        return read(path, config)
            .map(|r| (path.to_path_buf(), r))
            .map_err(|reason| refuse(format!("{}: {reason}", path.display())));
    }
    let mut reasons = Vec::new();
    for file in list(path).into_iter().rev() {
        match read(&file, config) {
            Ok(restored) => {
                for reason in &reasons {
                    tracing::warn!("skipped {reason}");
                }
                return Ok((file, restored));
            }
            Err(reason) => reasons.push(format!("{}: {reason}", file.display())),
        }
    }
    Err(refuse(if reasons.is_empty() {
        format!(
            "{}: no checkpoint_*.sdgc file to restart from",
            path.display()
        )
    } else {
        format!(
            "no valid checkpoint to restart from: {}",
            reasons.join("; ")
        )
    }))
}

/// Reads one checkpoint file for a run of `config`, or says why it cannot be used.
fn read(path: &Path, config: &Config) -> Result<Restored, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let payload = payload(&bytes)?;
    let cbor = miniz_oxide::inflate::decompress_to_vec_zlib(payload)
        .map_err(|e| format!("the compressed state is damaged ({:?})", e.status))?;
    let restored: Restored = ciborium::from_reader(&cbor[..])
        .map_err(|e| format!("the state cannot be decoded: {e}"))?;
    if let Some(key) = config_difference(&restored.header.config, &config_json(config)) {
        return Err(format!(
            "written by a run of another configuration ({key} differs); restart with the \
             configuration and overrides of the run that wrote it"
        ));
    }
    Ok(restored)
}

/// The payload of a checkpoint file's `bytes`, checked against its preamble.
fn payload(bytes: &[u8]) -> Result<&[u8], String> {
    if bytes.len() < PREAMBLE || &bytes[..8] != MAGIC {
        return Err("not an sdg checkpoint (no SDGCKPT header)".into());
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let format = word(8);
    if format != FORMAT {
        return Err(format!(
            "checkpoint format {format}, this sdg reads format {FORMAT}"
        ));
    }
    let length = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let payload = &bytes[PREAMBLE..];
    if payload.len() as u64 != length {
        return Err(format!(
            "truncated or extended: the state should be {length} bytes, the file holds {}",
            payload.len()
        ));
    }
    if crc32fast::hash(payload) != word(20) {
        return Err("checksum mismatch: the file is damaged".into());
    }
    Ok(payload)
}

/// The first key (dotted) where two configurations in JSON differ, ignoring [`FREE_KEYS`].
/// True when `config` moves the end time or the snapshot times of the run whose checkpoint
/// holds the configuration `saved`.
pub(crate) fn extends(saved: &str, config: &Config) -> bool {
    let (Ok(saved), Ok(current)) = (
        serde_json::from_str::<serde_json::Value>(saved),
        serde_json::to_value(config),
    ) else {
        return false;
    };
    EXTENSION_KEYS.iter().any(|key| {
        let pointer = format!("/{}", key.replace('.', "/"));
        saved.pointer(&pointer) != current.pointer(&pointer)
    })
}

fn config_difference(saved: &str, current: &str) -> Option<String> {
    let parse = |text: &str| serde_json::from_str::<serde_json::Value>(text).ok();
    let (Some(saved), Some(current)) = (parse(saved), parse(current)) else {
        return Some("the stored configuration".into());
    };
    first_difference(&saved, &current, "")
}

fn first_difference(a: &serde_json::Value, b: &serde_json::Value, at: &str) -> Option<String> {
    use serde_json::Value;
    if FREE_KEYS.contains(&at) || EXTENSION_KEYS.contains(&at) {
        return None;
    }
    let key = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match (a, b) {
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            keys.into_iter().find_map(|k| match (a.get(k), b.get(k)) {
                (Some(x), Some(y)) => first_difference(x, y, &key(k)),
                _ => {
                    let k = key(k);
                    let free =
                        FREE_KEYS.contains(&k.as_str()) || EXTENSION_KEYS.contains(&k.as_str());
                    (!free).then_some(k)
                }
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (x, y))| first_difference(x, y, &key(&i.to_string()))),
        _ => (a != b).then(|| {
            if at.is_empty() {
                "the configuration".into()
            } else {
                at.into()
            }
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damaged_preamble_or_payload_is_refused() {
        let payload = miniz_oxide::deflate::compress_to_vec_zlib(b"state", LEVEL);
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&FORMAT.to_le_bytes());
        bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        bytes.extend_from_slice(&payload);
        assert_eq!(self::payload(&bytes), Ok(&payload[..]));
        let reason = |b: &[u8]| self::payload(b).unwrap_err();
        assert!(reason(&bytes[..bytes.len() - 1]).contains("truncated"));
        assert!(reason(&bytes[..10]).contains("not an sdg checkpoint"));
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(reason(&flipped).contains("checksum"));
        let mut newer = bytes.clone();
        newer[8] = FORMAT as u8 + 1;
        assert!(reason(&newer).contains(&format!("format {}", FORMAT + 1)));
    }

    #[test]
    fn the_first_differing_key_is_named_and_free_keys_are_ignored() {
        let a = r#"{"material":{"density":1190,"e":3.24e9},"scheduler":{"threads":1},
                    "output":{"dir":"a","png":true},"interface":[{"strength":1},{"strength":2}]}"#;
        let same = r#"{"material":{"density":1190,"e":3.24e9},"scheduler":{"threads":4},
                    "output":{"dir":"b","png":true},"interface":[{"strength":1},{"strength":2}]}"#;
        assert_eq!(config_difference(a, same), None);
        let other = a.replace("\"e\":3.24e9", "\"e\":3.3e9");
        assert_eq!(config_difference(a, &other).as_deref(), Some("material.e"));
        let other = a.replace("{\"strength\":2}", "{\"strength\":3}");
        assert_eq!(
            config_difference(a, &other).as_deref(),
            Some("interface.1.strength")
        );
        let other = a.replace("\"png\":true", "\"png\":true,\"spacetime_mesh\":true");
        assert_eq!(
            config_difference(a, &other).as_deref(),
            Some("output.spacetime_mesh")
        );
        let ascii = a.replace("\"png\":true", "\"png\":true,\"vtu\":\"ascii\"");
        assert_eq!(config_difference(a, &ascii), None);
        let without_limits = a.replace(r#""scheduler":{"threads":1},"#, "");
        assert_eq!(config_difference(a, &without_limits), None);
    }
}
