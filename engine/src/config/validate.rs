//! Load-time validation: the checks of values that the schema's types cannot express.

use sdg_solver::interface::Law;

use super::conditions::{BoundaryKind, WaveName};
use super::material::PlaneName;
use super::mesh::{MeshKind, rectangle_key};
use super::schema::Config;

/// Shortest wall time between checkpoints, s (`checkpoint.every_wall_s`).
const MIN_WALL_CHECKPOINT_S: f64 = 1.0;

/// Most checkpoints that `checkpoint.every_sim_s` may ask for over a run.
const MAX_SIM_CHECKPOINTS: f64 = 1e5;

impl Config {
    /// Checks values that the schema's types cannot: returns `(key, reason)`.
    pub(super) fn validate(&self) -> Result<(), (String, String)> {
        let fail = |key: &str, reason: String| Err((key.to_string(), reason));
        self.material()
            .map_err(|e| (e.key.unwrap_or_default(), e.reason))?;
        let (start, end) = (self.time.start, self.time.end);
        if !start.is_finite() {
            return fail("time.start", format!("must be a time in s, got {start}"));
        }
        if !(end.is_finite() && self.time.span() > 0.0) {
            return fail(
                "time.end",
                format!("must be a time in s after time.start = {start:e}, got {end:e}"),
            );
        }
        let safety = self.pitch.safety;
        if !(safety > 0.0 && safety < 1.0) {
            return fail(
                "pitch.safety",
                format!(
                    "must be in (0, 1): a front facet at or above 1 is not causal, got {safety}"
                ),
            );
        }
        for (key, value) in [
            ("limits.max_tents", self.limits.max_tents),
            ("limits.max_wall_time_s", self.limits.max_wall_time_s),
        ] {
            if value.is_nan() || value <= 0.0 {
                return fail(key, format!("must be a positive number, got {value}"));
            }
        }
        if self.output.dir.as_os_str().is_empty() {
            return fail(
                "output.dir",
                "is empty: name a folder (default `out`)".into(),
            );
        }
        let c = &self.checkpoint;
        if c.dir.as_ref().is_some_and(|d| d.as_os_str().is_empty()) {
            return fail(
                "checkpoint.dir",
                "is empty: name a folder, or leave the key out for `checkpoints` in the output \
                 folder"
                    .into(),
            );
        }
        if c.every_wall_s.is_nan() || c.every_wall_s < MIN_WALL_CHECKPOINT_S {
            return fail(
                "checkpoint.every_wall_s",
                format!(
                    "must be a time of at least {MIN_WALL_CHECKPOINT_S} s (inf for none): a \
                     checkpoint pauses every worker to write the whole state, got {}",
                    c.every_wall_s
                ),
            );
        }
        if let Some(every) = c.every_sim_s {
            if !(every.is_finite() && every > 0.0) {
                return fail(
                    "checkpoint.every_sim_s",
                    format!("must be a positive time in s, got {every}"),
                );
            }
            let count = self.time.span() / every;
            if count > MAX_SIM_CHECKPOINTS {
                return fail(
                    "checkpoint.every_sim_s",
                    format!(
                        "{every:e} s makes {count:.3e} checkpoints over the run's {:e} s; at \
                         most {MAX_SIM_CHECKPOINTS:e}",
                        self.time.span()
                    ),
                );
            }
        }
        if c.keep == Some(0) {
            return fail(
                "checkpoint.keep",
                "must be at least 1: a restart needs a checkpoint".into(),
            );
        }
        self.validate_physics()?;
        self.validate_adapt()?;
        self.validate_fracture()?;
        let m = &self.mesh;
        let rectangle_keys = [
            ("mesh.width", m.width.is_some()),
            ("mesh.height", m.height.is_some()),
            ("mesh.nx", m.nx.is_some()),
            ("mesh.ny", m.ny.is_some()),
            ("mesh.diagonal", m.diagonal.is_some()),
            ("mesh.perturb", m.perturb.is_some()),
            ("mesh.seed", m.seed.is_some()),
            ("mesh.interface", !m.interface.is_empty()),
            ("mesh.side", !m.side.is_empty()),
        ];
        match m.kind {
            MeshKind::Rectangle => {
                if m.path.is_some() {
                    return fail("mesh.path", "is only used with mesh.kind = \"gmsh\"".into());
                }
                for key in ["mesh.width", "mesh.height", "mesh.nx", "mesh.ny"] {
                    if !rectangle_keys.iter().any(|&(k, set)| k == key && set) {
                        return fail(key, "is required with mesh.kind = \"rectangle\"".into());
                    }
                }
                self.rectangle()
                    .build()
                    .map(drop)
                    .or_else(|e| fail(&rectangle_key(&e), e.reason))?;
            }
            MeshKind::Gmsh => {
                if m.path.is_none() {
                    return fail("mesh.path", "is required with mesh.kind = \"gmsh\"".into());
                }
                if let Some((key, _)) = rectangle_keys.iter().find(|(_, set)| *set) {
                    return fail(key, "is only used with mesh.kind = \"rectangle\"".into());
                }
            }
        }
        Ok(())
    }

    /// Checks `[adapt]`.
    fn validate_adapt(&self) -> Result<(), (String, String)> {
        let a = &self.adapt;
        let fail = |key: &str, reason: String| Err((format!("adapt.{key}"), reason));
        if !(a.tol.is_finite() && a.tol > 0.0) {
            return fail("tol", format!("must be a positive number, got {}", a.tol));
        }
        if !(a.coarsen_ratio.is_finite() && a.coarsen_ratio > 1.0) {
            return fail(
                "coarsen_ratio",
                format!(
                    "must be a finite number above 1 (the lower tolerance is tol / ratio), got {}",
                    a.coarsen_ratio
                ),
            );
        }
        for (key, value) in [
            ("min_edge", a.min_edge),
            ("max_edge", a.max_edge),
            ("tip_edge", a.tip_edge),
            ("far_edge", a.far_edge),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && v > 0.0)
            {
                return fail(key, format!("must be a positive length in m, got {v}"));
            }
        }
        if let Some(e) = a.reference_energy.filter(|e| !(e.is_finite() && *e > 0.0)) {
            return fail(
                "reference_energy",
                format!("must be a positive energy in J/m, got {e}"),
            );
        }
        if a.fixed_reference && a.reference_energy.is_none() {
            return fail(
                "fixed_reference",
                "needs adapt.reference_energy, the energy the indicator is then measured against"
                    .to_string(),
            );
        }
        if let (Some(lo), Some(hi)) = (a.min_edge, a.max_edge)
            && 2.0 * lo > hi
        {
            return fail(
                "max_edge",
                format!("must be at least twice adapt.min_edge ({lo} m), got {hi} m"),
            );
        }
        for (i, z) in a.zone.iter().enumerate() {
            let key = |k: &str| format!("zone[{i}].{k}");
            if !z.from.iter().chain(&z.to).all(|x| x.is_finite()) {
                return fail(&key("from"), "the segment's ends must be finite".into());
            }
            if !(z.radius.is_finite() && z.radius >= 0.0) {
                return fail(
                    &key("radius"),
                    format!("must be a length >= 0 m, got {}", z.radius),
                );
            }
            if !(z.max_edge.is_finite() && z.max_edge > 0.0) {
                return fail(
                    &key("max_edge"),
                    format!("must be a positive length in m, got {}", z.max_edge),
                );
            }
            if let Some(lo) = a.min_edge.filter(|&lo| 2.0 * lo > z.max_edge) {
                return fail(
                    &key("max_edge"),
                    format!(
                        "must be at least twice adapt.min_edge ({lo} m), got {} m",
                        z.max_edge
                    ),
                );
            }
        }
        Ok(())
    }

    /// Checks `[solver]`, `[[boundary]]`, `[[interface]]`, `[exact]` and `[output]` times and
    /// points.
    fn validate_physics(&self) -> Result<(), (String, String)> {
        let order = self.solver.order;
        if !(1..=4).contains(&order) {
            return Err((
                "solver.order".into(),
                format!("must be 1 to 4, got {order}"),
            ));
        }
        let tol = self.solver.newton_tol;
        if !(tol > 0.0 && tol < 1.0) {
            return Err((
                "solver.newton_tol".into(),
                format!("must be in (0, 1) (a relative residual), got {tol}"),
            ));
        }
        if self.solver.newton_max_iter == 0 {
            return Err(("solver.newton_max_iter".into(), "must be at least 1".into()));
        }
        self.validate_interfaces()?;
        let antiplane = self.material.plane == PlaneName::Antiplane;
        let components = if antiplane { 1 } else { 2 };
        self.load_scales()?;
        let boundaries = self.boundaries();
        let mut seen: Vec<&str> = Vec::new();
        for (prefix, b) in &boundaries {
            let key = |k: &str| format!("{prefix}.{k}");
            if b.sides.is_empty() {
                return Err((key("sides"), "lists no side".into()));
            }
            for side in &b.sides {
                if seen.contains(&side.as_str()) {
                    return Err((
                        key("sides"),
                        format!("side `{side}` has a condition already"),
                    ));
                }
                seen.push(side);
            }
            let needs_value = matches!(b.kind, BoundaryKind::Traction | BoundaryKind::Velocity);
            let takes_history = needs_value || b.kind == BoundaryKind::Transmitting;
            match (&b.value, needs_value) {
                (None, true) => return Err((key("value"), "is required for this kind".into())),
                (Some(_), false) => {
                    return Err((key("value"), "is only used by traction and velocity".into()));
                }
                _ => {}
            }
            if b.incoming.is_some() && b.kind != BoundaryKind::Transmitting {
                return Err((key("incoming"), "is only used by transmitting".into()));
            }
            for (name, v) in [("value", &b.value), ("incoming", &b.incoming)] {
                if let Some(v) = v
                    && (v.len() != components || v.iter().any(|x| !x.is_finite()))
                {
                    let want = if antiplane {
                        "[z] in anti-plane"
                    } else {
                        "[x, y] (or [normal, tangential])"
                    };
                    return Err((
                        key(name),
                        format!("must be {components} finite numbers: {want}"),
                    ));
                }
            }
            if let Some(h) = &b.history {
                if !takes_history {
                    return Err((
                        key("history"),
                        "is only used by traction, velocity and transmitting".into(),
                    ));
                }
                h.to_history()
                    .map_err(|(k, r)| (key(&format!("history.{k}")), r))?;
            }
            if b.kind == BoundaryKind::Exact && self.exact.is_none() {
                return Err((key("kind"), "\"exact\" needs an [exact] section".into()));
            }
        }
        if let Some(e) = &self.exact {
            if e.wave == WaveName::P && antiplane {
                return Err((
                    "exact.wave".into(),
                    "anti-plane shear carries S waves only".into(),
                ));
            }
            if !(e.wavelength > 0.0 && e.wavelength.is_finite()) {
                return Err((
                    "exact.wavelength".into(),
                    format!("must be a positive length in m, got {}", e.wavelength),
                ));
            }
            for (k, v) in [
                ("angle_deg", e.angle_deg),
                ("amplitude", e.amplitude),
                ("center", e.center),
            ] {
                if !v.is_finite() {
                    return Err((format!("exact.{k}"), "must be finite".into()));
                }
            }
        }
        if let Some(t) = self
            .output
            .snapshot_times
            .iter()
            .find(|t| !(self.time.start..=self.time.end).contains(*t))
        {
            return Err((
                "output.snapshot_times".into(),
                format!(
                    "{t:e} s is outside [time.start, time.end] = [{:e}, {:e}] s (a run \
                     shortened with --set time.end=... needs its snapshot times too, e.g. \
                     --set 'output.snapshot_times=[]')",
                    self.time.start, self.time.end
                ),
            ));
        }
        if let Some(i) = self
            .output
            .interface_probes
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err((
                format!("output.interface_probes[{i}]"),
                "must be a point [x, y] of finite coordinates in m".into(),
            ));
        }
        Ok(())
    }

    /// Checks `[[interface]]`: tags named once, laws that the plane allows (the parameters are
    /// checked when an entry is read).
    fn validate_interfaces(&self) -> Result<(), (String, String)> {
        let mut seen: Vec<&str> = Vec::new();
        for (i, entry) in self.interface.iter().enumerate() {
            let key = |k: &str| format!("interface[{i}].{k}");
            if entry.tags.is_empty() {
                return Err((key("tags"), "lists no tag".into()));
            }
            for tag in &entry.tags {
                if seen.contains(&tag.as_str()) {
                    return Err((key("tags"), format!("tag `{tag}` has a law already")));
                }
                seen.push(tag);
            }
            if entry.law.name().is_in_plane_only() && self.material.plane == PlaneName::Antiplane {
                return Err((
                    key("law"),
                    "contact and cohesive laws need a normal direction, which anti-plane shear \
                     (material.plane = \"antiplane\") has not; use \"bonded\" or \"free\""
                        .into(),
                ));
            }
        }
        Ok(())
    }
}

impl Config {
    /// Checks `[fracture]`: `(key, reason)`.
    pub(super) fn validate_fracture(&self) -> Result<(), (String, String)> {
        let Some(f) = &self.fracture else {
            return Ok(());
        };
        let fail = |key: &str, reason: String| Err((format!("fracture.{key}"), reason));
        match self.law_of(&f.tag) {
            Some(Law::Damage(d)) if d.initial == 0.0 => {}
            _ => {
                return fail(
                    "tag",
                    format!(
                        "`{}` must be the tag of an [[interface]] with law = \"damage\" and no \
                         initial_damage: new crack edges start bonded",
                        f.tag
                    ),
                );
            }
        }
        for (i, tag) in f.from.iter().enumerate() {
            if !matches!(self.law_of(tag), Some(Law::Damage(_) | Law::Free)) {
                return fail(
                    &format!("from[{i}]"),
                    format!(
                        "`{tag}` must be the tag of an [[interface]] with law = \"damage\" or \
                         \"free\": a crack"
                    ),
                );
            }
        }
        if !(f.threshold.is_finite() && f.threshold > 0.0) {
            return fail(
                "threshold",
                format!("must be a positive stress in Pa, got {}", f.threshold),
            );
        }
        if !(f.shield_angle > 0.0 && f.shield_angle < 90.0) {
            return fail(
                "shield_angle",
                format!("must be in (0, 90) degrees, got {}", f.shield_angle),
            );
        }
        if !(f.snap > 0.0 && f.snap <= 0.5) {
            return fail(
                "snap",
                format!("must be a fraction of an edge in (0, 0.5], got {}", f.snap),
            );
        }
        if let Some(angle) = f.floor_angle
            && !(angle > 0.0 && angle <= 90.0)
        {
            return fail(
                "floor_angle",
                format!("must be in (0, 90] degrees, got {angle}"),
            );
        }
        if f.max_tip_speed.is_nan() || f.max_tip_speed <= 0.0 {
            return fail(
                "max_tip_speed",
                format!(
                    "must be a positive fraction of the Rayleigh speed (or inf), got {}",
                    f.max_tip_speed
                ),
            );
        }
        for (key, length) in [
            ("macro_length", f.macro_length),
            ("short_macro_length", f.short_macro_length),
            ("min_piece", f.min_piece),
            ("tangent_length", f.tangent_length),
            ("criterion_length", f.criterion_length),
        ] {
            if let Some(length) = length
                && !(length.is_finite() && length > 0.0)
            {
                return fail(key, format!("must be a positive length in m, got {length}"));
            }
        }
        f.defects().map(drop)
    }
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{BASE, INTERFACES, parse};

    fn key_of(text: &str, overrides: &[&str]) -> Option<String> {
        parse(text, overrides).unwrap_err().key
    }

    #[test]
    fn bad_interface_settings_name_the_key() {
        let text = format!("{BASE}{INTERFACES}");
        let error = |overrides: &[&str]| {
            let e = parse(&text, overrides).unwrap_err();
            (e.key.unwrap_or_default(), e.reason)
        };
        for (set, key, words) in [
            ("interface.0.friction=-0.1", "interface[0].friction", ">= 0"),
            ("interface.0.r_c=1e-6", "interface[0].r_c", "<= 0"),
            ("interface.0.r_s=-2e-6", "interface[0].r_s", ">= r_c"),
            ("interface.0.s_c=7e5", "interface[0].s_s", ">= s_c"),
            (
                "interface.0.law=glued",
                "interface[0].law",
                "unknown variant `glued`",
            ),
            (
                "interface.1.r_c=0.0",
                "interface[1].r_c",
                "not a parameter of law = \"free\"",
            ),
            (
                "interface.1.tags=[\"crack\"]",
                "interface[1].tags",
                "has a law already",
            ),
            ("interface.1.tags=[]", "interface[1].tags", "lists no tag"),
            ("material.plane=antiplane", "interface[0].law", "anti-plane"),
            ("solver.newton_tol=0.0", "solver.newton_tol", "(0, 1)"),
            ("solver.newton_tol=1.5", "solver.newton_tol", "(0, 1)"),
            (
                "solver.newton_max_iter=0",
                "solver.newton_max_iter",
                "at least 1",
            ),
            (
                "output.interface_probes=[[nan, 0.0]]",
                "output.interface_probes[0]",
                "finite",
            ),
            ("output.vtu=hex", "output.vtu", "unknown variant `hex`"),
            (
                "mesh.interface.1.from=[0.008, 0.0001]",
                "mesh.interface[1]",
                "grid node",
            ),
            (
                "mesh.side=[{from=[0.0, 0.0], to=[0.0, 0.001], tag=\"a\"}, \
                 {from=[0.0, 0.0], to=[0.0, 0.001], tag=\"left\"}]",
                "mesh.side[1]",
                "already names a side",
            ),
        ] {
            let (k, reason) = error(&[set]);
            assert_eq!(k, key, "{set}");
            assert!(reason.contains(words), "{set}: {reason}");
        }
        let missing = parse(&text.replace("s_s = 6e5\n", ""), &[]).unwrap_err();
        assert_eq!(missing.key.as_deref(), Some("interface[0].s_s"));
        assert!(missing.reason.contains("required with law = \"contact\""));
        // Cohesive parameters: required, positive, and only on the cohesive law.
        let cohesive = text.replacen(
            "law = \"contact\"\nfriction = 0.25\nr_c = -1e-6\nr_s = 0.0\ns_c = 0.0\ns_s = 6e5\n",
            "law = \"xu_needleman\"\nstrength = 324e6\ncritical_separation = 4e-7\n",
            1,
        );
        assert!(parse(&cohesive, &[]).is_ok(), "{cohesive}");
        for (set, key, words) in [
            ("interface.0.strength=0.0", "interface[0].strength", "> 0"),
            (
                "interface.0.critical_separation=-4e-7",
                "interface[0].critical_separation",
                "> 0",
            ),
            ("interface.0.r_c=1e-9", "interface[0].r_c", "<= 0"),
            (
                "interface.1.strength=1e6",
                "interface[1].strength",
                "not a parameter of law = \"free\"",
            ),
        ] {
            let e = parse(&cohesive, &[set]).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{set}");
            assert!(e.reason.contains(words), "{set}: {}", e.reason);
        }
        let e = parse(&cohesive.replace("strength = 324e6\n", ""), &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("interface[0].strength"));
        assert!(e.reason.contains("required with law = \"xu_needleman\""));
        let typo = parse(&text.replace("to = [0.008", "too = [0.008"), &[]).unwrap_err();
        assert_eq!(typo.key.as_deref(), Some("mesh.interface[1].too"));
    }

    /// The seed's clock on the branching plate: the end is written as given, although
    /// `3.6e-6 + 2.392e-6 - 2.392e-6` is not `3.6e-6` in floating point.
    #[test]
    fn the_clock_of_a_run_that_starts_before_zero() {
        let c = parse(BASE, &["time.start=-2.392e-6", "time.end=3.6e-6"]).unwrap();
        assert_eq!(c.time.span(), 3.6e-6 + 2.392e-6);
        assert_ne!(c.time.span() - 2.392e-6, 3.6e-6);
        assert_eq!(c.time.clock(c.time.span()), 3.6e-6);
        assert_eq!(c.time.clock(0.0), -2.392e-6);
        assert_eq!(c.time.elapsed(1e-6), 1e-6 + 2.392e-6);
    }

    #[test]
    fn errors_name_the_key() {
        assert_eq!(key_of(BASE, &["mesh.nx=abc"]).as_deref(), Some("mesh.nx"));
        assert_eq!(key_of(BASE, &["mesh.nx=1.5"]).as_deref(), Some("mesh.nx"));
        assert_eq!(
            key_of(BASE, &["material.density=-1"]).as_deref(),
            Some("material.density")
        );
        assert_eq!(
            key_of(BASE, &["material.poisson=0.5"]).as_deref(),
            Some("material.poisson")
        );
        assert_eq!(
            key_of(BASE, &["pitch.safety=1.0"]).as_deref(),
            Some("pitch.safety")
        );
        assert_eq!(key_of(BASE, &["time.end=0"]).as_deref(), Some("time.end"));
        assert_eq!(
            key_of(BASE, &["time.start=1e-6", "time.end=1e-6"]).as_deref(),
            Some("time.end")
        );
        assert_eq!(
            key_of(BASE, &["time.start=nan"]).as_deref(),
            Some("time.start")
        );
        assert!(parse(BASE, &["time.start=-2e-6", "time.end=-1e-6"]).is_ok());
        assert_eq!(
            key_of(BASE, &["time.start=-2e-6", "output.snapshot_times=[-3e-6]"]).as_deref(),
            Some("output.snapshot_times")
        );
        for set in [
            "limits.max_tents=0",
            "limits.max_tents=nan",
            "limits.max_tents=-1e9",
        ] {
            assert_eq!(key_of(BASE, &[set]).as_deref(), Some("limits.max_tents"));
        }
        assert_eq!(
            key_of(BASE, &["limits.max_wall_time_s=-3600"]).as_deref(),
            Some("limits.max_wall_time_s")
        );
        assert!(parse(BASE, &["limits.max_wall_time_s=inf"]).is_ok());
        for set in [
            "checkpoint.every_wall_s=0",
            "checkpoint.every_wall_s=nan",
            "checkpoint.every_sim_s=-1e-6",
            "checkpoint.every_sim_s=inf",
            "checkpoint.every_wall_s=1e-4",
            "checkpoint.every_sim_s=1e-15",
            "checkpoint.dir=''",
            "output.dir=''",
            "checkpoint.keep=0",
        ] {
            let key = set.split('=').next();
            assert_eq!(key_of(BASE, &[set]).as_deref(), key, "{set}");
        }
        assert!(parse(BASE, &["checkpoint.every_wall_s=inf", "checkpoint.keep=1"]).is_ok());
        assert_eq!(
            key_of(BASE, &["mesh.path=a.msh"]).as_deref(),
            Some("mesh.path")
        );
        assert_eq!(
            key_of(BASE, &["mesh.kind=gmsh", "mesh.path=a.msh"]).as_deref(),
            Some("mesh.width")
        );
        assert_eq!(
            key_of(BASE, &["mesh.perturb=0.3"]).as_deref(),
            Some("mesh.perturb")
        );
        assert_eq!(
            key_of(BASE, &["mesh.kind=tetra"]).as_deref(),
            Some("mesh.kind")
        );
        let unknown = parse(BASE, &["material.colour=1"]).unwrap_err();
        assert!(unknown.reason.contains("colour"), "{unknown}");
        let missing = parse(&BASE.replace("nx = 16\n", ""), &[]).unwrap_err();
        assert_eq!(missing.key.as_deref(), Some("mesh.nx"));
        let e = parse(BASE, &["mesh.nx.deep=1"]).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.key.as_deref()),
            ("--set mesh.nx.deep=1", Some("mesh.nx"))
        );
        assert!(
            parse(BASE, &["novalue"])
                .unwrap_err()
                .reason
                .contains("KEY=VALUE")
        );
    }
}
