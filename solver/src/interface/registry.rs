//! The registry of interface laws: the law of each interface tag.

use sdg_mesh::TagId;

use super::cohesive::CohesiveParams;
use super::contact::ContactParams;
use super::damage::DamageParams;

/// The law of an interface.
///
/// - [`Law::Bonded`]: the bonded ("first kind") solution (3.21)-(3.23); linear.
/// - [`Law::Free`]: both faces traction-free (separation, (3.34)); linear.
/// - [`Law::Contact`]: unilateral contact with Coulomb friction: area fractions separation
///   `1 - eta`, stick `eta gamma`, slip `eta (1 - gamma)` (3.43), targets as area-weighted
///   averages of the modal Riemann values (3.44); `eta = eta_delta(delta) eta_s(sI_n)` with cubic
///   smoothsteps (3.36)-(3.39); `gamma = 1` when `|sI_t| <= k <-sI_n>_+` (3.25); slip traction
///   `k <-sI_n>_+` in the direction of the stick traction (3.32). Nonlinear: patches with a
///   contact face are solved by Newton iterations.
/// - [`Law::XuNeedleman`]: cohesive fracture (seed 2.2.5, 2.5.2): the contact law whose
///   separated part carries the Xu-Needleman traction of the separation and slip (2.69) instead
///   of zero; in compression the faces are in contact. Nonlinear, like contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Perfectly bonded: the bonded Riemann solution (the default for untagged interior edges).
    Bonded,
    /// Both faces traction-free.
    Free,
    /// Unilateral contact with Coulomb friction.
    Contact(ContactParams),
    /// Xu-Needleman cohesive law, in contact under compression.
    XuNeedleman(CohesiveParams),
    /// Delayed damage, the debonded part in contact.
    Damage(DamageParams),
}

impl Law {
    /// True when the targets depend nonlinearly on the traces (a Newton patch).
    pub fn is_nonlinear(&self) -> bool {
        matches!(self, Law::Contact(_) | Law::XuNeedleman(_) | Law::Damage(_))
    }

    /// True for a fracture law (cohesive or damage), whose interface work is fracture energy.
    pub fn is_cohesive(&self) -> bool {
        matches!(self, Law::XuNeedleman(_) | Law::Damage(_))
    }
}

/// Laws per interface tag; interior edges without one are bonded.
#[derive(Clone, Debug, Default)]
pub struct Interfaces {
    by_tag: Vec<Option<Law>>,
}

impl Interfaces {
    /// Laws indexed by tag id.
    pub fn new(by_tag: Vec<Option<Law>>) -> Self {
        Self { by_tag }
    }

    /// The law on interior edges tagged `tag`.
    pub fn law(&self, tag: Option<TagId>) -> Law {
        tag.and_then(|t| self.by_tag.get(t as usize).copied().flatten())
            .unwrap_or(Law::Bonded)
    }

    /// True when some tag has a nonlinear law.
    pub fn any_nonlinear(&self) -> bool {
        self.by_tag.iter().flatten().any(Law::is_nonlinear)
    }

    /// True when some tag has a cohesive law.
    pub fn any_cohesive(&self) -> bool {
        self.by_tag.iter().flatten().any(Law::is_cohesive)
    }
}
