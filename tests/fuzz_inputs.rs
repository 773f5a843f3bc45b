//! In-process fuzzing of the two input readers (issue 15): the config loader (parse, overrides,
//! validation and [`Problem::setup`] with its mesh, as `sdg validate` runs them, without the
//! estimate or a solve) and the Gmsh MSH reader. Every input must end in a value or in an error
//! that `sdg` exits 2 with and that names the file and a reason; a panic fails the test and
//! saves the input under the target folder's `fuzz-crashes/`.
//!
//! Inputs are shipped files (`configs/`, `tests/data/*.msh`), generated small meshes and the
//! regression corpus (`tests/data/fuzz/config_seeds/`, `tests/data/fuzz/msh/`, replayed as they
//! are and mutated), each mutated a few times over. The default run (`SDG_FUZZ_CASES`, 10,000
//! inputs per reader) takes a few seconds; `docs/verification.md` ("Fuzzed inputs") records the
//! full runs.
//!
//! The generator is a hand-written SplitMix64 rather than proptest: the mutations are textual and
//! need no shrinking (a failing input is saved whole and cut down by hand into the corpus), and
//! a fixed 64-bit mixer keeps case `k` the same input on every machine and across dependency
//! updates, with no new dependency.

use std::cell::RefCell;
use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Once;
use std::time::{Duration, Instant};

use sdg_engine::{Config, EngineError, LoadedConfig, Problem};

/// SplitMix64 (Steele, Lea and Flood 2014): a seeded stream of 64-bit draws.
struct Rng(u64);

impl Rng {
    /// The stream of case `case` of a run with `seed`.
    fn new(seed: u64, case: u64) -> Self {
        Self(seed ^ case.wrapping_mul(0xd1b5_4a32_d192_ed03))
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A draw in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64) < p * (1u64 << 53) as f64
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The number of inputs per reader: `SDG_FUZZ_CASES`, else 10,000.
fn cases() -> u64 {
    std::env::var("SDG_FUZZ_CASES").map_or(10_000, |v| v.parse().expect("SDG_FUZZ_CASES"))
}

/// The run's seed: `SDG_FUZZ_SEED`, else a fixed one.
fn seed() -> u64 {
    std::env::var("SDG_FUZZ_SEED").map_or(15, |v| v.parse().expect("SDG_FUZZ_SEED"))
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The files of `dir` (relative to the repository) with extension `ext`, sorted.
fn files(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files
}

// ---------------------------------------------------------------------------------------------
// Panics: caught per input, with the message and place the panic hook saw.

thread_local! {
    /// Set while an input runs: the hook then records the panic here instead of printing it.
    static CAUGHT: RefCell<Option<Option<String>>> = const { RefCell::new(None) };
}

/// Runs `f` and returns its value, or the panic's message and place.
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let fuzzing = CAUGHT.with(|c| {
                let mut c = c.borrow_mut();
                c.as_mut()
                    .map(|slot| *slot = Some(info.to_string()))
                    .is_some()
            });
            if !fuzzing {
                previous(info);
            }
        }));
    });
    CAUGHT.with(|c| *c.borrow_mut() = Some(None));
    let result = catch_unwind(AssertUnwindSafe(f));
    let caught = CAUGHT.with(|c| c.borrow_mut().take()).flatten();
    result.map_err(|_| caught.unwrap_or_else(|| "a panic without a message".into()))
}

/// How one input ended.
enum Outcome {
    Accepted,
    /// Rejected as `sdg` rejects bad input: exit code 2, the file named, a reason.
    Rejected,
    /// Rejected in any other way: what was wrong with the error.
    Bad(String),
}

/// What a run of one reader saw.
#[derive(Default)]
struct Tally {
    accepted: usize,
    rejected: usize,
    /// Inputs left out before they ran (see [`too_big`]).
    skipped: usize,
    slowest: (Duration, String),
    /// Panics and bad rejections, with where the input was saved.
    failures: Vec<String>,
}

impl Tally {
    /// Records the outcome of input `name` (saved to `save` on failure).
    fn record(
        &mut self,
        name: &str,
        start: Instant,
        outcome: Result<Outcome, String>,
        save: impl FnOnce() -> PathBuf,
    ) {
        let took = start.elapsed();
        if took > self.slowest.0 {
            self.slowest = (took, name.to_string());
        }
        match outcome {
            Ok(Outcome::Accepted) => self.accepted += 1,
            Ok(Outcome::Rejected) => self.rejected += 1,
            Ok(Outcome::Bad(what)) => self.fail(format!("{name}: bad rejection: {what}"), save),
            Err(panic) => self.fail(format!("{name}: {panic}"), save),
        }
    }

    fn fail(&mut self, what: String, save: impl FnOnce() -> PathBuf) {
        // The first few are enough to act on.
        if self.failures.len() < 20 {
            self.failures
                .push(format!("{what}\n  input: {}", save().display()));
        }
    }

    /// Prints the counts and fails on any failure.
    fn finish(self, what: &str, start: Instant) {
        eprintln!(
            "{what}: {} inputs in {:.1} s: {} accepted, {} rejected, {} skipped, {} failures; \
             slowest {:.3} s ({})",
            self.accepted + self.rejected + self.skipped + self.failures.len(),
            start.elapsed().as_secs_f64(),
            self.accepted,
            self.rejected,
            self.skipped,
            self.failures.len(),
            self.slowest.0.as_secs_f64(),
            self.slowest.1,
        );
        assert!(self.failures.is_empty(), "{}", self.failures.join("\n"));
    }
}

/// Saves a failing input as `fuzz-crashes/NAME` under the target folder.
fn save(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

// ---------------------------------------------------------------------------------------------
// Shared text mutations.

/// Numbers and words that break parsers: zero, signs, the ends of the integer types, the ends
/// of f64, non-finite values, non-numbers.
const NASTY: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "2",
    "3",
    "0.0",
    "-0.0",
    "1e-300",
    "5e-324",
    "1e308",
    "-1e308",
    "1.8e308",
    "nan",
    "inf",
    "-inf",
    "NaN",
    "2147483647",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "0x10",
    "1_000",
    "1e",
    "--1",
    "\"\"",
    "\"x\"",
    "true",
    "x",
    "",
];

/// Characters that start or end syntax in TOML and MSH.
const SYNTAX: &[u8] = b"[]{}\"'=,.#$-+e \n\t\r\\0123456789";

/// One byte-level change: a bit flip, an inserted syntax byte or a deleted byte.
fn mutate_bytes(rng: &mut Rng, text: &str) -> String {
    let mut bytes = text.as_bytes().to_vec();
    if bytes.is_empty() {
        return String::new();
    }
    let at = rng.below(bytes.len());
    match rng.below(3) {
        0 => bytes[at] ^= 1 << rng.below(8),
        1 => bytes.insert(at, *rng.pick(SYNTAX)),
        _ => {
            bytes.remove(at);
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// One change to the line structure: delete, duplicate, swap or move lines, or truncate.
fn mutate_lines(rng: &mut Rng, lines: &mut Vec<String>) {
    if lines.is_empty() {
        return;
    }
    let i = rng.below(lines.len());
    match rng.below(5) {
        0 => {
            lines.remove(i);
        }
        1 => lines.insert(i, lines[i].clone()),
        2 => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
        3 => {
            let line = lines.remove(i);
            let j = rng.below(lines.len() + 1);
            lines.insert(j, line);
        }
        _ => {
            // Truncation inside a line, as a file cut short.
            lines.truncate(i + 1);
            let cut = rng.below(lines[i].len() + 1);
            let cut = (0..=cut)
                .rev()
                .find(|&c| lines[i].is_char_boundary(c))
                .unwrap();
            lines[i].truncate(cut);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Configs.

/// A config to mutate: its text and the file it is read as (relative mesh paths resolve
/// against that file's folder).
struct Seed {
    file: PathBuf,
    text: String,
}

impl Seed {
    /// The overrides a corpus file lists in its `# --set KEY=VALUE` lines.
    fn overrides(&self) -> Vec<String> {
        let sets = self.text.lines().filter_map(|l| l.strip_prefix("# --set "));
        sets.map(str::to_string).collect()
    }
}

/// The shipped configs and the config regression corpus.
fn config_seeds() -> Vec<Seed> {
    files("configs", "toml")
        .into_iter()
        .chain(files("tests/data/fuzz/config_seeds", "toml"))
        .map(|file| Seed {
            text: std::fs::read_to_string(&file).unwrap(),
            file,
        })
        .collect()
}

/// `key = value` with the key's leading indentation.
fn key_value(line: &str) -> Option<(&str, &str)> {
    let t = line.trim_start();
    if t.starts_with('[') || t.starts_with('#') {
        return None;
    }
    let (key, value) = t.split_once('=')?;
    // A trailing comment, unless the value is a string that may hold `#`.
    let value = match value.trim_start().starts_with(['"', '\'']) {
        true => value,
        false => value.split_once('#').map_or(value, |(v, _)| v),
    };
    Some((key.trim(), value.trim()))
}

/// The dotted keys of `text` (`mesh.nx`, `boundary.0.kind`) with their values, for overrides.
fn dotted_keys(text: &str) -> Vec<(String, String)> {
    let mut keys = Vec::new();
    let mut table = String::new();
    let mut arrays: Vec<(String, usize)> = Vec::new();
    for line in text.lines() {
        let t = line.trim();
        if let Some(name) = t.strip_prefix("[[").and_then(|t| t.split_once("]]")) {
            let name = name.0.trim().to_string();
            let n = match arrays.iter_mut().find(|(a, _)| *a == name) {
                Some((_, n)) => {
                    *n += 1;
                    *n
                }
                None => {
                    arrays.push((name.clone(), 0));
                    0
                }
            };
            table = format!("{name}.{n}.");
        } else if let Some(name) = t.strip_prefix('[').and_then(|t| t.split_once(']')) {
            table = format!("{}.", name.0.trim());
        } else if let Some((key, value)) = key_value(line) {
            keys.push((format!("{table}{key}"), value.to_string()));
        }
    }
    keys
}

/// A value to put where a config value was: a nasty literal, the old number scaled, another
/// type, a long array or string. Cell counts stay small enough to build (see [`too_big`]).
fn config_value(rng: &mut Rng, key: &str, old: &str, pool: &[String]) -> String {
    if key.ends_with("nx") || key.ends_with("ny") {
        return rng
            .pick(&[
                "0",
                "-1",
                "1",
                "3",
                "300",
                "4294967295",
                "4294967296",
                "1000000000",
                "3.5",
                "\"16\"",
            ])
            .to_string();
    }
    if rng.chance(0.7) {
        return typed_value(rng, old, pool);
    }
    match rng.below(9) {
        0..=2 => rng.pick(NASTY).to_string(),
        3 => match old.parse::<f64>() {
            Ok(x) => format!(
                "{:e}",
                x * 10f64.powi(*rng.pick(&[-300, -30, -3, -1, 1, 3, 30, 300]))
            ),
            Err(_) => rng.pick(NASTY).to_string(),
        },
        4 => rng.pick(pool).clone(),
        5 => {
            let item = rng.pick(&["0.0", "1e-3", "nan", "[0.0, 0.0]", "\"left\""]);
            let n = *rng.pick(&[0, 1, 2, 3, 5, 2000]);
            format!("[{}]", vec![*item; n].join(", "))
        }
        6 => format!("\"{}\"", "a".repeat(*rng.pick(&[0, 1, 10_000]))),
        7 => rng
            .pick(&[
                "{}",
                "{ kind = \"smooth\" }",
                "{ kind = \"smooth\", ramp = -1.0 }",
                "[[0.0, 0.0], [1e308, -1e308]]",
                "[[]]",
                "1979-05-27T07:32:00Z",
                "'''\nx'''",
            ])
            .to_string(),
        _ => format!("{}", rng.next() as i64 >> rng.below(64)),
    }
}

/// A value of the same TOML type as `old`: a number at the ends of its range, non-finite or
/// scaled, another string of the seeds, an array with one such element changed or one more
/// or fewer element.
fn typed_value(rng: &mut Rng, old: &str, pool: &[String]) -> String {
    let number = |rng: &mut Rng, old: &str| -> String {
        let integer = old.parse::<i64>().is_ok();
        match (integer, rng.below(3)) {
            (true, 0 | 1) => rng
                .pick(&[
                    "0",
                    "-1",
                    "1",
                    "2",
                    "7",
                    "4294967296",
                    "9223372036854775807",
                ])
                .to_string(),
            (false, 0 | 1) => rng
                .pick(&[
                    "0.0", "-0.0", "-1.0", "nan", "inf", "-inf", "1e308", "-1e308", "5e-324",
                    "1e-300", "0.5", "1.0",
                ])
                .to_string(),
            _ => match old.parse::<f64>() {
                Ok(x) => {
                    let power = *rng.pick(&[-300, -30, -3, -1, 0, 1, 3, 30, 300]);
                    format!("{:e}", -x * 10f64.powi(power) * *rng.pick(&[1.0, -1.0]))
                }
                Err(_) => "0".to_string(),
            },
        }
    };
    if old.parse::<f64>().is_ok() {
        return number(rng, old);
    }
    if old.starts_with('"') {
        let strings: Vec<&String> = pool.iter().filter(|v| v.starts_with('"')).collect();
        return match rng.below(4) {
            0 => "\"\"".to_string(),
            _ => rng.pick(&strings).to_string(),
        };
    }
    if let Some(inner) = old.strip_prefix('[').and_then(|o| o.strip_suffix(']'))
        && !inner.contains('[')
    {
        let mut items: Vec<String> = inner
            .split(',')
            .map(|i| i.trim().to_string())
            .filter(|i| !i.is_empty())
            .collect();
        match rng.below(4) {
            0 => {
                items.pop();
            }
            1 => items.push(items.last().cloned().unwrap_or_else(|| "0.0".into())),
            _ if !items.is_empty() => {
                let k = rng.below(items.len());
                items[k] = match items[k].parse::<f64>() {
                    Ok(_) => number(rng, &items[k]),
                    Err(_) => rng.pick(pool).clone(),
                };
            }
            _ => {}
        }
        return format!("[{}]", items.join(", "));
    }
    rng.pick(pool).clone()
}

/// One structural or value change to the lines of a config.
fn mutate_config(rng: &mut Rng, lines: &mut Vec<String>, keys: &[String], values: &[String]) {
    let entries: Vec<usize> = (0..lines.len())
        .filter(|&i| key_value(&lines[i]).is_some())
        .collect();
    let headers: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].trim_start().starts_with('['))
        .collect();
    match rng.below(12) {
        0..=5 if !entries.is_empty() => {
            let i = *rng.pick(&entries);
            let (key, old) = key_value(&lines[i]).unwrap();
            let value = config_value(rng, key, old, values);
            lines[i] = format!("{key} = {value}");
        }
        6 if !entries.is_empty() => {
            let i = *rng.pick(&entries);
            let (key, value) = key_value(&lines[i]).unwrap();
            let new = match rng.below(4) {
                0 => rng.pick(keys).clone(),
                1 => format!("{key}s"),
                2 => key.to_uppercase(),
                _ => format!("{key}.{key}"),
            };
            lines[i] = format!("{new} = {value}");
        }
        7 if !headers.is_empty() => {
            let i = *rng.pick(&headers);
            let name = lines[i].trim().trim_matches(['[', ']']).to_string();
            lines[i] = match rng.below(4) {
                0 if lines[i].trim().starts_with("[[") => format!("[{name}]"),
                0 => format!("[[{name}]]"),
                1 => format!(
                    "[{}]",
                    rng.pick(&["mesh", "x", "boundary", "mesh.interface"])
                ),
                2 => format!("[{name}.{name}]"),
                _ => String::new(),
            };
        }
        8 => {
            let i = rng.below(lines.len() + 1);
            let key = rng.pick(keys).clone();
            let value = config_value(rng, &key, "", values);
            lines.insert(i, format!("{key} = {value}"));
        }
        _ => mutate_lines(rng, lines),
    }
}

/// An override `--set` spec: a key of a seed with a value for it, or a malformed spec.
fn override_spec(rng: &mut Rng, dotted: &[(String, String)], values: &[String]) -> String {
    if rng.chance(0.3) {
        return rng
            .pick(&[
                "",
                "=",
                "mesh",
                "mesh.nx",
                "=1",
                "mesh..nx=1",
                ".mesh.nx=1",
                "mesh.nx.x=1",
                "boundary.99.kind=\"free\"",
                "boundary.-1.kind=\"free\"",
                "boundary.18446744073709551616.kind=\"free\"",
                "interface.0=1",
                "a.b.c.d=1",
                "mesh.nx=[",
                "time.end=nan",
                "time=1",
                "mesh=1",
                "boundary=[]",
                "mesh.interface.0.from=[1e308, 1e308]",
                "output.interface_probes=[[0.0, 0.0]]",
            ])
            .to_string();
    }
    let (key, old) = rng.pick(dotted);
    let value = config_value(rng, key, old, values);
    format!("{key}={value}")
}

/// True when the largest `nx` and `ny` in `text` and `overrides` make a grid of more than a
/// million nodes that the rectangle generator would build: it takes seconds and gigabytes, a
/// cost `[limits]` bounds only at the estimate, after setup.
fn too_big(text: &str, overrides: &[String]) -> bool {
    // A TOML integer: decimal with `_`, or hexadecimal, octal or binary.
    let integer = |v: &str| {
        let v = v.trim().replace('_', "");
        let radix = [("0x", 16), ("0o", 8), ("0b", 2)];
        match radix.iter().find(|(p, _)| v.starts_with(p)) {
            Some(&(p, r)) => u64::from_str_radix(&v[p.len()..], r).ok(),
            None => v.parse::<u64>().ok(),
        }
    };
    let count = |key: &str| {
        let sets = overrides.iter().filter_map(|s| s.split_once('='));
        text.lines()
            .filter_map(key_value)
            .chain(sets)
            .filter(|(k, _)| k.trim().rsplit('.').next() == Some(key))
            .filter_map(|(_, v)| integer(v))
            .max()
            .unwrap_or(0)
    };
    let nodes = (count("nx") + 1).saturating_mul(count("ny") + 1);
    nodes > 1_000_000 && nodes <= u32::MAX as u64 / 8
}

/// Loads `text` (read as `file`) with `overrides` and sets the problem up, as `sdg validate`
/// does before its estimate.
fn check_config(file: &Path, text: &str, overrides: &[String]) -> Outcome {
    let source = file.display().to_string();
    let named = |e: &sdg_engine::ConfigError| {
        let by_file = e.file == source || e.file.starts_with("--set ");
        if by_file && !e.reason.trim().is_empty() {
            Outcome::Rejected
        } else {
            Outcome::Bad(format!("{e:?}"))
        }
    };
    let config = match Config::parse(text, &source, overrides) {
        Ok(config) => config,
        Err(e) => return named(&e),
    };
    let loaded = LoadedConfig {
        config,
        file: file.to_path_buf(),
        overrides: Vec::new(),
    };
    let mesh_file = loaded.config.mesh.path.as_ref().map(|p| loaded.resolve(p));
    match Problem::setup(loaded) {
        Ok(_) => Outcome::Accepted,
        Err(EngineError::Config(e)) => named(&sdg_engine::config::attribute(e, overrides)),
        // `CONFIG: mesh.path: FILE[:LINE]: reason` of the mesh reader.
        Err(e @ EngineError::Mesh { .. })
            if mesh_file.is_some_and(|f| {
                e.to_string()
                    .strip_prefix(&format!("{}: mesh.path: ", file.display()))
                    .and_then(|m| m.strip_prefix(&*f.to_string_lossy()))
                    .and_then(|rest| rest.split_once(": "))
                    .is_some_and(|(_, reason)| !reason.trim().is_empty())
            }) =>
        {
            Outcome::Rejected
        }
        Err(e) => Outcome::Bad(format!("exit {}: {e:?}", e.exit_code())),
    }
}

/// What the seeds hold, to draw keys and values from.
struct Pool {
    /// Keys, plain (`nx`) and dotted (`mesh.nx`, `boundary.0.kind`).
    keys: Vec<String>,
    /// Values of any key, the paths of the MSH files as seen from `configs/`, paths to no MSH
    /// file.
    values: Vec<String>,
    /// Dotted keys with their values.
    dotted: Vec<(String, String)>,
}

impl Pool {
    fn of(seeds: &[Seed]) -> Self {
        let mut pool = Self {
            keys: Vec::new(),
            values: Vec::new(),
            dotted: Vec::new(),
        };
        for s in seeds {
            for (k, v) in s.text.lines().filter_map(key_value) {
                pool.keys.push(k.to_string());
                pool.values.push(v.to_string());
            }
            pool.dotted.extend(dotted_keys(&s.text));
        }
        pool.keys.extend(pool.dotted.iter().map(|(k, _)| k.clone()));
        pool.keys.sort();
        pool.keys.dedup();
        for dir in ["tests/data", "tests/data/fuzz/msh"] {
            for f in files(dir, "msh") {
                let name = f.file_name().unwrap().to_string_lossy();
                pool.values.push(format!("\"../{dir}/{name}\""));
            }
        }
        // Paths that are no MSH file: a folder, a device that never ends.
        pool.values.extend(["\".\"".into(), "\"/dev/zero\"".into()]);
        pool
    }
}

/// Generates a config: a seed with 1 to 8 mutations, sometimes byte changes and overrides.
/// Returns the seed's index, the text and the overrides.
fn config_case(rng: &mut Rng, seeds: &[Seed], pool: &Pool) -> (usize, String, Vec<String>) {
    let s = rng.below(seeds.len());
    let mut lines: Vec<String> = seeds[s].text.lines().map(str::to_string).collect();
    let n = if rng.chance(0.8) {
        1 + rng.below(3)
    } else {
        1 + rng.below(8)
    };
    for _ in 0..n {
        mutate_config(rng, &mut lines, &pool.keys, &pool.values);
    }
    let mut text = lines.join("\n") + "\n";
    if rng.chance(0.08) {
        for _ in 0..1 + rng.below(3) {
            text = mutate_bytes(rng, &text);
        }
    }
    let overrides = if rng.chance(0.2) {
        (0..1 + rng.below(2))
            .map(|_| override_spec(rng, &pool.dotted, &pool.values))
            .collect()
    } else {
        Vec::new()
    };
    (s, text, overrides)
}

/// Every seed as it is, then `SDG_FUZZ_CASES` mutated configs.
#[test]
fn configs_load_or_are_rejected_with_a_reason() {
    let seeds = config_seeds();
    let pool = Pool::of(&seeds);
    let start = Instant::now();
    let mut tally = Tally::default();
    for s in &seeds {
        let t0 = Instant::now();
        let outcome = guarded(|| check_config(&s.file, &s.text, &s.overrides()));
        tally.record(&s.file.display().to_string(), t0, outcome, || {
            s.file.clone()
        });
    }
    let seed = seed();
    for case in 0..cases() {
        let mut rng = Rng::new(seed, case);
        let (s, text, overrides) = config_case(&mut rng, &seeds, &pool);
        if too_big(&text, &overrides) {
            tally.skipped += 1;
            continue;
        }
        let t0 = Instant::now();
        let file = &seeds[s].file;
        let outcome = guarded(|| check_config(file, &text, &overrides));
        let name = format!("config case {case} (from {})", file.display());
        tally.record(&name, t0, outcome, || {
            let mut saved = String::new();
            for o in &overrides {
                writeln!(saved, "# --set {o}").unwrap();
            }
            // Mesh paths as seen from `tests/data/fuzz/config_seeds/`, where it may go.
            let text = text.replace("../tests/data/", "../../");
            save(&format!("config-{case}.toml"), &(saved + &text))
        });
    }
    tally.finish("configs", start);
}

// ---------------------------------------------------------------------------------------------
// MSH files.

/// A valid MSH 4.1 mesh of an `nx` x `ny` grid of right triangles, with physical curves on its
/// sides, an interior interface line, shuffled node tags, and sometimes one defect the counts
/// agree with: a repeated, inverted, degenerate, flat or overlapping triangle, a node twice, a
/// line off the triangulation, a node off the plane or far away.
fn grid_msh(rng: &mut Rng) -> String {
    let (nx, ny) = (1 + rng.below(4), 1 + rng.below(4));
    let (w, h) = (*rng.pick(&[1.0, 4e-3, 1e-6]), *rng.pick(&[1.0, 2e-3, 1e-6]));
    let z = *rng.pick(&[0.0, -3.5, 1e3]);
    let base = *rng.pick(&[1u64, 1, 7, 1 << 40]);
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let n_nodes = (nx + 1) * (ny + 1);
    // Node k gets tag base + perm[k].
    let mut perm: Vec<u64> = (0..n_nodes as u64).collect();
    if rng.chance(0.5) {
        for k in (1..perm.len()).rev() {
            perm.swap(k, rng.below(k + 1));
        }
    }
    let tag = |k: usize| base + perm[k];
    let mut points: Vec<[f64; 3]> = (0..n_nodes)
        .map(|k| {
            let (i, j) = (k % (nx + 1), k / (nx + 1));
            [i as f64 * w / nx as f64, j as f64 * h / ny as f64, z]
        })
        .collect();
    let mut triangles: Vec<[u64; 3]> = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([tag(a), tag(b), tag(c)]);
            triangles.push([tag(a), tag(c), tag(d)]);
        }
    }
    // Curves 1-4: bottom, right, top, left; 5: the interior line j = ny / 2 (when ny > 1).
    let mut curves: Vec<Vec<[u64; 2]>> = vec![Vec::new(); 5];
    for i in 0..nx {
        curves[0].push([tag(id(i, 0)), tag(id(i + 1, 0))]);
        curves[2].push([tag(id(i, ny)), tag(id(i + 1, ny))]);
        if ny > 1 {
            curves[4].push([tag(id(i, ny / 2)), tag(id(i + 1, ny / 2))]);
        }
    }
    for j in 0..ny {
        curves[1].push([tag(id(nx, j)), tag(id(nx, j + 1))]);
        curves[3].push([tag(id(0, j)), tag(id(0, j + 1))]);
    }
    let mut extra_node = None;
    if rng.chance(0.5) {
        let t = rng.below(triangles.len());
        let u = rng.below(triangles.len());
        match rng.below(9) {
            0 => triangles.push(triangles[t]),
            1 => triangles[t].swap(1, 2),
            2 => triangles[t][1] = triangles[t][0],
            3 => triangles[t] = [tag(id(0, 0)), tag(id(nx, 0)), tag(id(nx / 2, 0))],
            4 => triangles[t] = triangles[u],
            5 => triangles.push([triangles[t][0], triangles[t][1], triangles[u][2]]),
            6 => curves[0].push([tag(id(0, 0)), tag(id(nx, ny))]),
            7 => points[rng.below(n_nodes)][2] += 1.0,
            _ => extra_node = Some([1e300, -1e300, z]),
        }
    }
    let names = rng.chance(0.7);
    let mut out = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    if names {
        out += "$PhysicalNames\n6\n1 1 \"bottom\"\n1 2 \"right\"\n1 3 \"top\"\n1 4 \"left\"\n\
                1 5 \"crack\"\n2 9 \"plate\"\n$EndPhysicalNames\n";
    }
    if rng.chance(0.2) {
        out += "$Comments\nfuzz\n$EndComments\n";
    }
    // Entities: no points, 5 curves with physical tags 1-5, 1 surface.
    out += "$Entities\n0 5 1 0\n";
    for c in 1..=5 {
        writeln!(out, "{c} 0 0 0 {w} {h} 0 1 {c} 0").unwrap();
    }
    writeln!(out, "1 0 0 0 {w} {h} 0 1 9 0\n$EndEntities").unwrap();
    // One node block on the surface (its nodes in tag order of the grid), and an extra node.
    let total = n_nodes + usize::from(extra_node.is_some());
    let (lo, hi) = (base, base + total as u64 - 1);
    writeln!(
        out,
        "$Nodes\n{} {total} {lo} {hi}",
        1 + usize::from(extra_node.is_some())
    )
    .unwrap();
    writeln!(out, "2 1 0 {n_nodes}").unwrap();
    for k in 0..n_nodes {
        writeln!(out, "{}", tag(k)).unwrap();
    }
    for p in &points {
        writeln!(out, "{:e} {:e} {:e}", p[0], p[1], p[2]).unwrap();
    }
    if let Some(p) = extra_node {
        writeln!(out, "0 1 0 1\n{hi}\n{:e} {:e} {:e}", p[0], p[1], p[2]).unwrap();
    }
    out += "$EndNodes\n";
    let lines: usize = curves.iter().map(Vec::len).sum();
    let blocks = 1 + curves.iter().filter(|c| !c.is_empty()).count();
    writeln!(
        out,
        "$Elements\n{blocks} {} 1 {}",
        lines + triangles.len(),
        lines + triangles.len()
    )
    .unwrap();
    let mut element = 0;
    for (c, lines) in curves.iter().enumerate().filter(|(_, c)| !c.is_empty()) {
        writeln!(out, "1 {} 1 {}", c + 1, lines.len()).unwrap();
        for [a, b] in lines {
            element += 1;
            writeln!(out, "{element} {a} {b}").unwrap();
        }
    }
    writeln!(out, "2 1 2 {}", triangles.len()).unwrap();
    for [a, b, c] in &triangles {
        element += 1;
        writeln!(out, "{element} {a} {b} {c}").unwrap();
    }
    out + "$EndElements\n"
}

/// One change to one whitespace-separated token of a line: a nasty value, the token plus or
/// minus one, or the token of another line.
fn mutate_token(rng: &mut Rng, lines: &mut [String]) {
    if lines.is_empty() {
        return;
    }
    let i = rng.below(lines.len());
    let mut tokens: Vec<String> = lines[i].split_whitespace().map(str::to_string).collect();
    if tokens.is_empty() {
        return;
    }
    let k = rng.below(tokens.len());
    tokens[k] = match rng.below(4) {
        0 | 1 => rng.pick(NASTY).to_string(),
        2 => match tokens[k].parse::<i64>() {
            Ok(v) => (v + *rng.pick(&[-1, 1, 1000])).to_string(),
            Err(_) => rng.pick(NASTY).to_string(),
        },
        _ => {
            let other = rng.pick(lines);
            other.split_whitespace().next().unwrap_or("").to_string()
        }
    };
    if rng.chance(0.2) {
        tokens.push(rng.pick(NASTY).to_string());
    }
    lines[i] = tokens.join(" ");
}

/// Parses `text` as the MSH file `source`; a rejection must name the file, a line of the text
/// (or 0) and a reason.
fn check_msh(text: &str, source: &str) -> Outcome {
    match sdg_mesh::gmsh::parse_msh(text, source) {
        Ok(_) => Outcome::Accepted,
        Err(e)
            if e.file == source
                && e.line <= text.lines().count()
                && !e.reason.trim().is_empty() =>
        {
            Outcome::Rejected
        }
        Err(e) => Outcome::Bad(format!("{e:?}")),
    }
}

/// Every MSH seed as it is, then `SDG_FUZZ_CASES` generated and mutated files.
#[test]
fn msh_files_load_or_are_rejected_with_a_reason() {
    let seeds: Vec<(String, String)> = files("tests/data", "msh")
        .into_iter()
        .chain(files("tests/data/fuzz/msh", "msh"))
        .map(|p| {
            (
                p.display().to_string(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    let start = Instant::now();
    let mut tally = Tally::default();
    for (name, text) in &seeds {
        let t0 = Instant::now();
        let outcome = guarded(|| check_msh(text, name));
        tally.record(name, t0, outcome, || name.into());
    }
    let seed = seed();
    for case in 0..cases() {
        let mut rng = Rng::new(seed, case);
        let text = if rng.chance(0.6) {
            grid_msh(&mut rng)
        } else {
            rng.pick(&seeds).1.clone()
        };
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        let n = *rng.pick(&[0, 1, 1, 1, 2, 3, 6]);
        for _ in 0..n {
            if rng.chance(0.6) {
                mutate_token(&mut rng, &mut lines);
            } else {
                mutate_lines(&mut rng, &mut lines);
            }
        }
        let mut text = lines.join("\n") + "\n";
        if rng.chance(0.15) {
            text = mutate_bytes(&mut rng, &text);
        }
        let name = format!("msh case {case}");
        let t0 = Instant::now();
        let outcome = guarded(|| check_msh(&text, "fuzz.msh"));
        tally.record(&name, t0, outcome, || {
            save(&format!("msh-{case}.msh"), &text)
        });
    }
    tally.finish("msh", start);
}
