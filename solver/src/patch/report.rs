//! What a patch solve reports: per element and per patch energies, work and diagnostics, and
//! the state of an interface at a point.

use crate::interface::Mode;

/// Energy terms and diagnostics of one solved element, in scaled units (physical: times the
/// density; see [`crate::system`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ElementReport {
    /// Energy entering through the inflow face.
    pub energy_in: f64,
    /// Energy leaving through the outflow face (now part of the front).
    pub energy_out: f64,
    /// `energy_out` split as `[kinetic, strain, flux]` (see `norms::FrontEnergy`).
    pub energy_out_parts: [f64; 3],
    /// Net power entering through the vertical faces, integrated over them.
    pub vertical_work: f64,
    /// Part of `vertical_work` through the domain boundary.
    pub boundary_work: f64,
    /// Energy taken out of the element by interface faces (minus their part of
    /// `vertical_work`): summed over both sides of a face, the work absorbed by the interface.
    pub interface_work: f64,
    /// Part of `interface_work` done by tangential tractions on tangential velocity jumps of
    /// contact faces: friction.
    pub friction_dissipation: f64,
    /// Part of `interface_work` done on cohesive faces: the work of separation spent so far
    /// (fracture energy; for the reversible Xu-Needleman law, partly stored until the faces
    /// separate fully).
    pub fracture_work: f64,
    /// Numerical dissipation from the jumps against the targets: a sum of non-negative terms.
    pub dissipation: f64,
    /// Dissipation from the energy balance `energy_in - energy_out + vertical_work`; equal to
    /// `dissipation` to round-off when the element equations hold.
    pub dissipation_balance: f64,
    /// `|sum over faces of the momentum target flux|` (scaled units): zero to round-off when
    /// the element balances linear momentum.
    pub momentum_imbalance: f64,
    /// Sum over faces of the magnitude of the momentum target flux (scaled units).
    pub momentum_flux: f64,
    /// `momentum_imbalance / momentum_flux`: zero to round-off when the element balances
    /// linear momentum and its fluxes are not themselves round-off (an element at rest reads
    /// anything up to 1).
    pub momentum_residual: f64,
}

/// Totals over one patch.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PatchReport {
    /// Elements solved.
    pub elements: usize,
    /// Unknowns of the linear system.
    pub dofs: usize,
    /// Sum of the element reports' fields.
    pub energy_in: f64,
    /// See [`ElementReport::energy_out`].
    pub energy_out: f64,
    /// See [`ElementReport::boundary_work`].
    pub boundary_work: f64,
    /// See [`ElementReport::interface_work`].
    pub interface_work: f64,
    /// See [`ElementReport::friction_dissipation`].
    pub friction_dissipation: f64,
    /// See [`ElementReport::fracture_work`].
    pub fracture_work: f64,
    /// See [`ElementReport::dissipation`].
    pub dissipation: f64,
    /// Largest [`ElementReport::momentum_residual`] of its elements.
    pub momentum_residual: f64,
    /// Largest [`ElementReport::momentum_imbalance`] of its elements.
    pub momentum_imbalance: f64,
    /// Largest [`ElementReport::momentum_flux`] of its elements.
    pub momentum_flux: f64,
    /// Newton iterations (linear solves) of a patch with nonlinear faces; zero for a linear
    /// patch.
    pub newton_iterations: usize,
    /// The cohesive indicator's measure: the work of the mismatch between the cohesive traction
    /// of the faces' separation and of the elements' displacement jump (see
    /// `ContactFaces::cohesive_mismatch`), scaled units like `dissipation`.
    pub cohesive_mismatch: f64,
    /// Wall time assembling the patch's system, s (measured: not the same from run to run).
    pub assembly_s: f64,
    /// Wall time solving it (the ring elimination, or the Newton iterations), s.
    pub solve_s: f64,
    /// Wall time evaluating the results (energies, displacements, interface states), s.
    pub evaluation_s: f64,
}

/// A patch whose outflow energy exceeds this multiple of the most energy the body has held
/// (initial energy plus boundary work, the patch's own included) has blown up: the scheme's
/// upwind fluxes only ever dissipate ([`PatchReport::blows_up`]).
pub const BLOW_UP: f64 = 10.0;

/// Energy terms of a [`PatchReport`] that add up ([`PatchReport::energy_terms`]).
pub const ENERGY_TERMS: usize = 7;

/// Momentum diagnostics of a [`PatchReport`] whose largest is kept
/// ([`PatchReport::momentum_terms`]).
pub const MOMENTUM_TERMS: usize = 3;

impl PatchReport {
    /// True when the patch carries more than [`BLOW_UP`] times `held` out, `held` being what the
    /// body has held before it (scaled units, as the report's) plus the patch's own boundary
    /// work when positive.
    pub fn blows_up(&self, held: f64) -> bool {
        self.energy_out > BLOW_UP * (held + self.boundary_work.max(0.0))
    }

    /// The first of the report's energy terms, momentum residual and cohesive mismatch that is
    /// not finite, with its field's name: a patch that has one must not be stored.
    pub fn first_non_finite(&self) -> Option<(&'static str, f64)> {
        [
            ("energy_in", self.energy_in),
            ("energy_out", self.energy_out),
            ("boundary_work", self.boundary_work),
            ("interface_work", self.interface_work),
            ("friction_dissipation", self.friction_dissipation),
            ("fracture_work", self.fracture_work),
            ("dissipation", self.dissipation),
            ("momentum_residual", self.momentum_residual),
            ("cohesive_mismatch", self.cohesive_mismatch),
        ]
        .into_iter()
        .find(|(_, v)| !v.is_finite())
    }

    /// Adds `other`'s energy terms to these totals and keeps the largest of each momentum
    /// diagnostic; sums in the order of the calls.
    pub fn accumulate(&mut self, other: &PatchReport) {
        self.add_terms(other.energy_terms(), other.momentum_terms());
    }

    /// The energy terms that add up over patches: energy in and out, boundary work, interface
    /// work, friction dissipation, fracture work, dissipation (scaled units).
    pub fn energy_terms(&self) -> [f64; ENERGY_TERMS] {
        [
            self.energy_in,
            self.energy_out,
            self.boundary_work,
            self.interface_work,
            self.friction_dissipation,
            self.fracture_work,
            self.dissipation,
        ]
    }

    /// The momentum diagnostics whose largest is kept over patches: residual, imbalance, flux.
    pub fn momentum_terms(&self) -> [f64; MOMENTUM_TERMS] {
        [
            self.momentum_residual,
            self.momentum_imbalance,
            self.momentum_flux,
        ]
    }

    /// Adds `energy` (in the order of [`Self::energy_terms`]) to the energy terms and keeps the
    /// larger of each momentum diagnostic and `momentum` ([`Self::momentum_terms`]).
    pub fn add_terms(&mut self, energy: [f64; ENERGY_TERMS], momentum: [f64; MOMENTUM_TERMS]) {
        let [
            e_in,
            e_out,
            boundary,
            interface,
            friction,
            fracture,
            dissipation,
        ] = energy;
        self.energy_in += e_in;
        self.energy_out += e_out;
        self.boundary_work += boundary;
        self.interface_work += interface;
        self.friction_dissipation += friction;
        self.fracture_work += fracture;
        self.dissipation += dissipation;
        let [residual, imbalance, flux] = momentum;
        self.momentum_residual = self.momentum_residual.max(residual);
        self.momentum_imbalance = self.momentum_imbalance.max(imbalance);
        self.momentum_flux = self.momentum_flux.max(flux);
    }
}

impl From<&ElementReport> for PatchReport {
    /// The energy terms and momentum diagnostics of one element, as a patch of no elements.
    fn from(r: &ElementReport) -> Self {
        Self {
            energy_in: r.energy_in,
            energy_out: r.energy_out,
            boundary_work: r.boundary_work,
            interface_work: r.interface_work,
            friction_dissipation: r.friction_dissipation,
            fracture_work: r.fracture_work,
            dissipation: r.dissipation,
            momentum_residual: r.momentum_residual,
            momentum_imbalance: r.momentum_imbalance,
            momentum_flux: r.momentum_flux,
            ..Self::default()
        }
    }
}

/// The state of a contact interface at one point, physical units, in the frame of the face
/// (normal, tangential; each value is the same whichever side the normal points from).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceSample {
    /// Time, s.
    pub time: f64,
    /// Target traction `s*`, Pa.
    pub traction: [f64; 2],
    /// Bonded Riemann traction `sI`, Pa.
    pub bonded_traction: [f64; 2],
    /// Normal separation, m.
    pub delta: f64,
    /// Tangential slip, m.
    pub slip: f64,
    /// Damage `D` in effect (the debonded fraction) with the damage law; 0 with other laws.
    pub damage: f64,
    /// Jump of the target velocities `[[v*]]`, m/s.
    pub velocity_jump: [f64; 2],
    /// Contact area fraction.
    pub eta: f64,
    /// Stick flag.
    pub gamma: f64,
    /// The mode with the largest area fraction.
    pub mode: Mode,
}

/// A contact face's cut by the plane of a snapshot ([`PatchSolver::snapshot_cuts`]).
///
/// [`PatchSolver::snapshot_cuts`]: super::PatchSolver::snapshot_cuts
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceCut {
    /// The plane's time, s (on the run's clock from 0).
    pub time: f64,
    /// The segment's ends, m.
    pub ends: [[f64; 2]; 2],
    /// The interface at each end; `None` where the patch cannot sample it.
    pub samples: [Option<InterfaceSample>; 2],
}
