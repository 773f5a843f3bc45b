//! The environment of OpenMPI's `mpirun` in the tests, as `.ci/run` sets it: as root
//! (containers, CI), on more ranks than cores, and over loopback only. One file for both
//! crates' tests: `tests/common/mod.rs` declares it, `distributed/tests/mpirun.rs` includes it
//! by path (the distributed crate cannot depend on the root crate's test helpers).

/// OpenMPI's variables and their values, for `Command::envs`.
pub const MPIRUN_ENV: [(&str, &str); 5] = [
    ("OMPI_ALLOW_RUN_AS_ROOT", "1"),
    ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
    ("OMPI_MCA_rmaps_base_oversubscribe", "1"),
    ("OMPI_MCA_btl", "self,vader"),
    ("OMPI_MCA_oob_tcp_if_include", "lo"),
];
