//! The TOML run configuration: schema, command-line overrides and load-time validation.
//!
//! Every key is documented in `docs/reference/config.md`. Units are SI. Unknown keys, wrong types and
//! unphysical values are rejected with an error naming the file and the key.

mod conditions;
mod derived;
mod error;
mod fracture;
mod interface;
mod load;
mod loading;
mod material;
mod mesh;
mod overrides;
mod schema;
mod settings;
mod validate;

pub use conditions::{
    BoundaryConfig, BoundaryKind, ExactConfig, ExactKind, HistoryConfig, HistoryKind, ProfileName,
    WaveName,
};
pub use fracture::FractureConfig;
pub use interface::{
    CohesiveConfig, ContactConfig, DamageConfig, InterfaceConfig, LawConfig, LawName,
};
pub use loading::{LoadScales, LoadingConfig};
pub use material::{MaterialConfig, PlaneName};
pub(crate) use mesh::rectangle_key;
pub use mesh::{DiagonalName, MeshConfig, MeshKind, SegmentConfig};
pub use settings::{
    AdaptConfig, CheckpointConfig, LimitsConfig, OutputConfig, PitchConfig, SchedulerConfig,
    SolverConfig, TimeConfig, VtuFormat, ZoneConfig,
};

pub use error::ConfigError;
pub use load::LoadedConfig;
pub use overrides::attribute;
pub use schema::Config;

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) const BASE: &str = r#"
[mesh]
kind = "rectangle"
width = 0.016
height = 0.01
nx = 16
ny = 10

[material]
young = 3.24e9
poisson = 0.35
density = 1190.0
plane = "strain"

[time]
end = 1e-6
"#;

    pub(super) fn parse(text: &str, overrides: &[&str]) -> Result<Config, ConfigError> {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Config::parse(text, "test.toml", &o)
    }

    /// Two interface segments and a contact law on one of them.
    pub(super) const INTERFACES: &str = r#"
[[mesh.interface]]
from = [0.0, 0.005]
to = [0.004, 0.005]
tag = "crack"

[[mesh.interface]]
from = [0.008, 0.0]
to = [0.008, 0.004]
tag = "joint"

[[interface]]
tags = ["crack"]
law = "contact"
friction = 0.25
r_c = -1e-6
r_s = 0.0
s_c = 0.0
s_s = 6e5

[[interface]]
tags = ["joint"]
law = "free"
"#;

    #[test]
    fn syntax_errors_give_the_line() {
        let e = parse(&format!("{BASE}\n[time\n"), &[]).unwrap_err();
        assert!(e.reason.contains("line 18"), "{e}");
        assert_eq!(e.to_string().split(':').next(), Some("test.toml"));
    }
}
