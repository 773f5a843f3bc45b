//! `study.slurm`: a Slurm array job whose task `K` runs case `K` of the study.

use std::path::{Path, PathBuf};

use super::file::Study;
use crate::error::EngineError;
use crate::output::write_atomic;

/// Writes `out/study.slurm` for the `cases` cases of `study`, run by the `sdg` binary
/// `program` on `threads` threads per task, and makes `out/cases` (where the tasks' Slurm logs
/// go). Paths in the script are absolute, so it can be submitted from anywhere. Returns the
/// script's path.
pub fn write_slurm(
    study: &Study,
    cases: usize,
    program: &Path,
    out: &Path,
    threads: usize,
) -> Result<PathBuf, EngineError> {
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| EngineError::io(p, e));
    let (file, out_abs, program) = (absolute(&study.file)?, absolute(out)?, absolute(program)?);
    let logs = out_abs.join("cases");
    std::fs::create_dir_all(&logs).map_err(|e| EngineError::io(&logs, e))?;
    let q = |p: &Path| quote(&p.display().to_string());
    let script = format!(
        "#!/bin/bash\n\
         # Written by `sdg study {file} --slurm`: array task K runs case K of the study\n\
         # (`sdg study STUDY --case K`) into {out}/cases/K. Submit it with\n\
         #   sbatch {out}/study.slurm\n\
         # and, once the tasks have ended, gather the cases with\n\
         #   sdg study {file} --collect --output {out}\n\
         # A task whose case has finished with the same config does nothing: submit the array\n\
         # again to run what failed or did not finish. Two minutes before the time limit Slurm\n\
         # sends SIGTERM to the task (--signal): its case writes a checkpoint and stops (exit 3),\n\
         # and the next submission goes on from there. Edit the #SBATCH lines for your cluster\n\
         # (remove one '#' to enable a line).\n\
         #SBATCH --job-name=sdg-study-{stem}\n\
         ##SBATCH --partition=PARTITION\n\
         ##SBATCH --account=ACCOUNT\n\
         ##SBATCH --time=01:00:00\n\
         ##SBATCH --mem=2G\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task={threads}\n\
         #SBATCH --output={logs}/slurm-%A_%a.out\n\
         #SBATCH --signal=B:TERM@120\n\
         \n\
         set -u\n\
         case=${{SLURM_ARRAY_TASK_ID:?submit with sbatch: the array task id is the case}}\n\
         exec {sdg} study {study} --case \"$case\" --output {out_q} \\\n    \
         --threads \"${{SLURM_CPUS_PER_TASK:-{threads}}}\" --quiet\n",
        file = file.display(),
        out = out_abs.display(),
        stem = study.stem(),
        last = cases.saturating_sub(1),
        logs = logs.display(),
        sdg = q(&program),
        study = q(&file),
        out_q = q(&out_abs),
    );
    write_atomic(out, "study.slurm", script.as_bytes())
}

/// `text` as one shell word, in single quotes.
fn quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', "'\\''"))
}

#[cfg(test)]
mod tests {
    #[test]
    fn words_are_quoted_for_the_shell() {
        assert_eq!(super::quote("/a b/it's"), "'/a b/it'\\''s'");
    }
}
