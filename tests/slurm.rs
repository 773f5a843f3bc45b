//! The Slurm job scripts of `examples/slurm` (issue 69), run by bash with the real `sdg` and
//! stand-ins for Slurm's commands on `PATH`, written here: `squeue` prints the time left that
//! the test sets, `sbatch` and `scontrol` record how they were called. Checked: the time left
//! becomes `--max-wall-time`, SIGTERM to the batch shell reaches sdg, exit 3 resubmits
//! (`run.sbatch`) or requeues (`sweep.sbatch`) and the next job resumes with `--restart`
//! until the run finishes, and the caps on resubmissions hold. `mpi.sbatch` (issue 68) runs
//! under a stand-in `srun` that starts the ranks with `mpirun` on this machine, stops at its
//! wall time, resubmits itself and resumes over the ranks, or, with an sdg built without the
//! feature `mpi`, refuses before starting any.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The most a job may take here.
const LIMIT: Duration = Duration::from_secs(300);

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fake Slurm in a temporary folder: `bin/` with the stand-ins, `left` (what `squeue -o %L`
/// prints), `sbatch.log`, `scontrol.log` and `srun.log` (one line per call: `SDG_RESUBMIT=N
/// ARGS...`, `ARGS...` and `ARGS...`).
struct Slurm(tempfile::TempDir);

impl Slurm {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let bin = dir.path().join("bin");
        std::fs::create_dir(&bin).unwrap();
        let stubs = [
            ("squeue", r#"cat "$FAKE_SLURM/left""#),
            (
                "sbatch",
                r#"echo "SDG_RESUBMIT=${SDG_RESUBMIT:-} $*" >>"$FAKE_SLURM/sbatch.log"
echo "Submitted batch job 999""#,
            ),
            ("scontrol", r#"echo "$*" >>"$FAKE_SLURM/scontrol.log""#),
            // Records its options, then starts the command on SLURM_NTASKS ranks here.
            (
                "srun",
                r#"echo "$*" >>"$FAKE_SLURM/srun.log"
while [ "${1#-}" != "$1" ]; do shift; done
exec mpirun -n "$SLURM_NTASKS" "$@""#,
            ),
        ];
        for (name, body) in stubs {
            let path = bin.join(name);
            std::fs::write(&path, format!("#!/bin/bash\n{body}\n")).unwrap();
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        Self(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }

    /// Sets what `squeue` says is left of the job (`%L`: `[D-][[H:]M:]S` or `UNLIMITED`).
    fn left(&self, left: &str) {
        std::fs::write(self.path("left"), format!("{left}\n")).unwrap();
    }

    /// The lines `log` holds (`sbatch.log`, `scontrol.log`).
    fn calls(&self, log: &str) -> Vec<String> {
        let text = std::fs::read_to_string(self.path(log)).unwrap_or_default();
        text.lines().map(str::to_string).collect()
    }

    /// `bash examples/slurm/SCRIPT ARGS` as Slurm would start it: job `id`, 2 cores, the
    /// submit folder the repository, the stand-ins first on `PATH`, the real sdg in `SDG`.
    fn job(&self, script: &str, id: u32, args: &[&str], env: &[(&str, &str)]) -> Command {
        let path = format!(
            "{}:{}",
            self.path("bin").display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let mut command = Command::new("bash");
        command
            .arg(repo().join("examples/slurm").join(script))
            .args(args)
            .env("PATH", path)
            .env("FAKE_SLURM", self.0.path())
            .env("SDG", env!("CARGO_BIN_EXE_sdg"))
            .env("SLURM_JOB_ID", id.to_string())
            .env("SLURM_CPUS_PER_TASK", "2")
            .env("SLURM_SUBMIT_DIR", repo())
            .envs(env.iter().copied())
            .env_remove("SDG_FAULT")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        command
    }
}

/// Waits for the job at most [`LIMIT`]: its exit code and standard output.
fn finish(mut child: Child) -> (i32, String) {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            panic!("a job took more than {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

/// The pid of the child of `shell` that listens to signals (sdg's thread `signals`), once it
/// does.
fn listening_child(shell: &mut Child) -> u32 {
    let start = Instant::now();
    loop {
        let tasks = std::fs::read_dir(format!("/proc/{}/task", shell.id())).unwrap();
        let children: Vec<u32> = (tasks.flatten())
            .filter_map(|t| std::fs::read_to_string(t.path().join("children")).ok())
            .flat_map(|t| {
                let pids: Vec<u32> = t
                    .split_whitespace()
                    .filter_map(|p| p.parse().ok())
                    .collect();
                pids
            })
            .collect();
        let listens = |pid: &u32| {
            (std::fs::read_dir(format!("/proc/{pid}/task"))
                .into_iter()
                .flatten())
            .flatten()
            .any(|t| {
                std::fs::read_to_string(t.path().join("comm")).is_ok_and(|c| c.trim() == "signals")
            })
        };
        if let Some(pid) = children.into_iter().find(listens) {
            return pid;
        }
        assert!(shell.try_wait().unwrap().is_none(), "the job ended first");
        assert!(start.elapsed() < LIMIT, "no sdg listening");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The lines of `OUT/jobs.log`, without their dates: `job ID: sdg exited N`.
fn jobs(out: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(out.join("jobs.log")).unwrap_or_default();
    (text.lines())
        .map(|l| l.split_once(' ').map_or(l, |(_, rest)| rest).to_string())
        .collect()
}

/// `run.sbatch` over three jobs of a plane wave of seconds: the first stops at the
/// `--max-wall-time` the time left gives (3 s, less a margin of 1 s), the second by
/// SIGTERM to the batch shell only (Slurm's `--signal=B:TERM`), each exits 3 and resubmits
/// itself; the third resumes and finishes. A job past `SDG_MAX_RESUBMITS` does not resubmit.
#[test]
fn run_sbatch_resubmits_on_exit_3_until_the_run_finishes() {
    let slurm = Slurm::new();
    let out = slurm.path("out");
    let script = repo().join("examples/slurm/run.sbatch");
    // About 4 s on two idle cores: longer than the first job's 2 s.
    let args = [
        "--set",
        "mesh.nx=32",
        "--set",
        "mesh.ny=32",
        "--set",
        "time.end=4e-6",
        "--set",
        "output.png=false",
    ];
    let out_env = out.to_str().unwrap();
    let env = |resubmit: &'static str| {
        [
            ("SDG_CONFIG", "configs/plane_wave.toml"),
            ("SDG_OUT", out_env),
            ("SDG_MARGIN_S", "1"),
            ("SDG_RESUBMIT", resubmit),
        ]
    };
    let resubmitted = |job: u32, resubmit: u32| {
        format!(
            "SDG_RESUBMIT={resubmit} --dependency=afterany:{job} {} {}",
            script.display(),
            args.join(" ")
        )
    };

    // Job 101: 3 s left, a margin of 1 s.
    slurm.left("00:03");
    let (code, text) = finish(
        slurm
            .job("run.sbatch", 101, &args, &env("0"))
            .spawn()
            .unwrap(),
    );
    assert_eq!(
        code, 0,
        "the job that resubmitted itself ends with 0: {text}"
    );
    assert!(text.contains("--max-wall-time 2"), "{text}");
    let restart = format!("--restart {}/checkpoints", out.display());
    assert!(!text.contains(&restart), "{text}");
    assert_eq!(slurm.calls("sbatch.log"), [resubmitted(101, 1)]);
    assert_eq!(jobs(&out), ["job 101: sdg exited 3"]);

    // Job 102: no limit known; Slurm's SIGTERM to the batch shell.
    slurm.left("UNLIMITED");
    let mut job = slurm
        .job("run.sbatch", 102, &args, &env("1"))
        .spawn()
        .unwrap();
    listening_child(&mut job);
    let status = Command::new("kill")
        .args(["-TERM", &job.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let (code, text) = finish(job);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains(&restart), "{text}");
    assert!(!text.contains("--max-wall-time"), "{text}");
    let calls = slurm.calls("sbatch.log");
    assert_eq!(calls, [resubmitted(101, 1), resubmitted(102, 2)]);

    // Job 103: a day left; it resumes and finishes.
    slurm.left("1-00:00:00");
    let (code, text) = finish(
        slurm
            .job("run.sbatch", 103, &args, &env("2"))
            .spawn()
            .unwrap(),
    );
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("--max-wall-time 86399"), "{text}");
    assert!(text.contains("finished:"), "{text}");
    assert_eq!(slurm.calls("sbatch.log").len(), 2, "no resubmission");
    assert_eq!(
        jobs(&out),
        [
            "job 101: sdg exited 3",
            "job 102: sdg exited 3",
            "job 103: sdg exited 0"
        ]
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["checkpoint"]["restarted_from"].is_string());

    // A job at the cap, SDG_MAX_RESUBMITS, stopped by its wall time in a fresh folder: exit 3
    // and no resubmission.
    let capped = slurm.path("capped");
    slurm.left("00:03");
    let env = [
        ("SDG_CONFIG", "configs/plane_wave.toml"),
        ("SDG_OUT", capped.to_str().unwrap()),
        ("SDG_MARGIN_S", "1"),
        ("SDG_RESUBMIT", "2"),
        ("SDG_MAX_RESUBMITS", "2"),
    ];
    let (code, text) = finish(slurm.job("run.sbatch", 104, &args, &env).spawn().unwrap());
    assert_eq!(code, 3, "{text}");
    assert!(text.contains("not resubmitting"), "{text}");
    assert_eq!(slurm.calls("sbatch.log").len(), 2, "no resubmission");
}

/// `sweep.sbatch`, task 1 of array job 200: stopped by its wall time (3 s left, a margin of
/// 1 s), it requeues itself (`scontrol requeue 200_1`); requeued for the last time allowed
/// (`SLURM_RESTART_COUNT`), it resumes with `--restart` and, stopped again, does not requeue.
#[test]
fn sweep_sbatch_requeues_a_stopped_task_and_resumes_it() {
    let slurm = Slurm::new();
    let sweep = slurm.path("sweep");
    let env = |restarts: &'static str| {
        [
            ("SDG_SWEEP", sweep.to_str().unwrap().to_string()),
            ("SDG_MARGIN_S", "1".into()),
            ("SLURM_ARRAY_TASK_ID", "1".into()),
            ("SLURM_ARRAY_JOB_ID", "200".into()),
            ("SLURM_RESTART_COUNT", restarts.into()),
        ]
    };
    let task = sweep.join("task_001");
    slurm.left("00:03");
    let first = env("0");
    let first: Vec<(&str, &str)> = first.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let (code, text) = finish(slurm.job("sweep.sbatch", 201, &[], &first).spawn().unwrap());
    assert_eq!(code, 3, "{text}");
    assert!(text.contains("--max-wall-time 2"), "{text}");
    assert_eq!(slurm.calls("scontrol.log"), ["requeue 200_1"]);
    assert_eq!(
        std::fs::read_to_string(task.join("overrides.txt")).unwrap(),
        "boundary.1.incoming=[4.0e7,0.0]\n"
    );

    let last = env("5");
    let last: Vec<(&str, &str)> = last.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let (code, text) = finish(slurm.job("sweep.sbatch", 202, &[], &last).spawn().unwrap());
    assert_eq!(code, 3, "{text}");
    assert!(
        text.contains(&format!("--restart {}/checkpoints", task.display())),
        "{text}"
    );
    assert!(text.contains("not again"), "{text}");
    assert_eq!(slurm.calls("scontrol.log").len(), 1, "no second requeue");
    assert_eq!(
        jobs(&task),
        ["job 201: sdg exited 3", "job 202: sdg exited 3"]
    );
}

/// `mpi.sbatch` on 3 tasks, a plane wave of a microsecond. With the feature `mpi`: through the
/// stand-in `srun` (the default plugin `--mpi=pmix`, and `SDG_SRUN_MPI`), then with
/// `SDG_LAUNCHER=mpirun` on 2 tasks, each run finishing with `ranks` = the task count in
/// `summary.json`; an unknown launcher exits 2. Without: exit 2 before any rank starts, as for
/// a binary that does not run.
#[test]
fn mpi_sbatch_runs_one_rank_per_task_or_refuses_a_build_without_mpi() {
    let slurm = Slurm::new();
    let args = [
        "--set",
        "mesh.nx=8",
        "--set",
        "mesh.ny=8",
        "--set",
        "time.end=1e-6",
        "--set",
        "output.snapshot_times=[]",
        "--set",
        "output.png=false",
    ];
    let job = |id: u32, tasks: &str, out: &Path, env: &[(&str, &str)]| {
        let mut job = slurm.job("mpi.sbatch", id, &args, &[]);
        job.env_remove("SDG_CONFIG")
            .env_remove("SDG_LAUNCHER")
            .env_remove("SDG_SRUN_MPI")
            .env("SLURM_NTASKS", tasks)
            .env("SDG_OUT", out)
            .envs(common::mpirun::MPIRUN_ENV)
            .envs(env.iter().copied());
        finish(job.spawn().unwrap())
    };
    let ranks = |out: &Path| {
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        summary["ranks"].clone()
    };

    let out = slurm.path("missing");
    let (code, text) = job(300, "3", &out, &[("SDG", "/nonexistent/sdg")]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("cannot run SDG=/nonexistent/sdg"), "{text}");
    assert!(!out.exists(), "nothing written");

    if !cfg!(feature = "mpi") {
        let out = slurm.path("refused");
        let (code, text) = job(301, "3", &out, &[]);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains("built without MPI"), "{text}");
        assert!(slurm.calls("srun.log").is_empty(), "no rank started");
        assert!(!out.exists(), "nothing written");
        return;
    }

    let out = slurm.path("srun");
    let (code, text) = job(301, "3", &out, &[]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("finished:"), "{text}");
    assert_eq!(ranks(&out), 3);
    assert_eq!(jobs(&out), ["job 301: sdg exited 0 (3 ranks)"]);
    let sdg = env!("CARGO_BIN_EXE_sdg");
    let call = format!(
        "--mpi=pmix --cpus-per-task=2 --kill-on-bad-exit=1 {sdg} run configs/plane_wave.toml \
         --mpi --threads 2 --output {} --log-level info {}",
        out.display(),
        args.join(" ")
    );
    assert_eq!(slurm.calls("srun.log"), [call]);

    let out = slurm.path("pmi2");
    let (code, text) = job(302, "3", &out, &[("SDG_SRUN_MPI", "pmi2")]);
    assert_eq!(code, 0, "{text}");
    let calls = slurm.calls("srun.log");
    assert!(calls[1].starts_with("--mpi=pmi2 "), "{calls:?}");

    let out = slurm.path("mpirun");
    let (code, text) = job(303, "2", &out, &[("SDG_LAUNCHER", "mpirun")]);
    assert_eq!(code, 0, "{text}");
    assert!(
        text.contains("mpirun --mca odls_base_sigkill_timeout 20 -n 2 --map-by slot:PE=2 "),
        "{text}"
    );
    assert_eq!(ranks(&out), 2);
    assert_eq!(slurm.calls("srun.log").len(), 2, "srun not used");

    let out = slurm.path("unknown");
    let (code, text) = job(304, "2", &out, &[("SDG_LAUNCHER", "ssh")]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("must be srun or mpirun"), "{text}");
    assert!(!out.exists(), "nothing written");
}

/// `mpi.sbatch` over two jobs of 2 ranks, a plane wave of seconds: the first stops at the
/// `--max-wall-time` the time left gives (3 s, less a margin of 1 s), every rank checkpoints,
/// and the job resubmits itself; the second resumes with `--restart` and finishes.
#[cfg(feature = "mpi")]
#[test]
fn mpi_sbatch_resubmits_on_exit_3_and_the_ranks_resume() {
    let slurm = Slurm::new();
    let out = slurm.path("out");
    // About 7 s over 2 ranks on two idle cores: longer than the first job's 2 s.
    let args = [
        "--set",
        "mesh.nx=16",
        "--set",
        "mesh.ny=16",
        "--set",
        "time.end=4e-5",
        "--set",
        "output.snapshot_times=[]",
        "--set",
        "output.png=false",
    ];
    let job = |id: u32, resubmit: &str| {
        let mut job = slurm.job("mpi.sbatch", id, &args, &[]);
        job.env_remove("SDG_CONFIG")
            .env_remove("SDG_LAUNCHER")
            .env_remove("SDG_SRUN_MPI")
            .env("SLURM_NTASKS", "2")
            .env("SDG_OUT", &out)
            .env("SDG_MARGIN_S", "1")
            .env("SDG_RESUBMIT", resubmit)
            .envs(common::mpirun::MPIRUN_ENV);
        finish(job.spawn().unwrap())
    };
    slurm.left("00:03");
    let (code, text) = job(305, "0");
    assert_eq!(
        code, 0,
        "the job that resubmitted itself ends with 0: {text}"
    );
    assert!(text.contains("--max-wall-time 2"), "{text}");
    let script = repo().join("examples/slurm/mpi.sbatch");
    let resubmitted = format!(
        "SDG_RESUBMIT=1 --dependency=afterany:305 {} {}",
        script.display(),
        args.join(" ")
    );
    assert_eq!(slurm.calls("sbatch.log"), [resubmitted]);

    slurm.left("1-00:00:00");
    let (code, text) = job(306, "1");
    assert_eq!(code, 0, "{text}");
    let restart = format!("--restart {}/checkpoints", out.display());
    assert!(text.contains(&restart), "{text}");
    assert!(text.contains("finished:"), "{text}");
    assert_eq!(slurm.calls("sbatch.log").len(), 1, "no resubmission");
    assert_eq!(
        jobs(&out),
        [
            "job 305: sdg exited 3 (2 ranks)",
            "job 306: sdg exited 0 (2 ranks)"
        ]
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["checkpoint"]["restarted_from"].is_string());
    assert_eq!(summary["ranks"], 2);
}
