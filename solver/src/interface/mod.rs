//! Interface laws: the target values on the vertical faces above a tagged interior edge
//! (seed 3.2.1-3.2.2, 3.3.1).
//!
//! An interface is a flag on mesh edges, not a cut: both sides are elements of the same patch and
//! the law replaces the bonded Riemann solution between them. Each law maps the characteristics
//! arriving at the face, `w_a = s_a - Z v_a` from side a and `w_b = s_b + Z v_b` from side b (per
//! frame direction, scaled units, normal `m` from a to b), and the interface state (the normal
//! separation `delta`, m) to side a's targets: velocity `v*_a` and traction `s*`. Side b's targets
//! are the same law seen from b: swap `w_a` and `w_b` (the frame flips with the normal, which
//! leaves frame tractions and characteristics unchanged).
//!
//! Every target keeps side a's outgoing characteristic (`s* - Z v*_a = w_a`), so the numerical
//! dissipation `(v_a - v*_a) . (s_a - s*)` of each side stays non-negative whatever the law.
//!
//! The separation `[[u]]` (normal `delta`, tangential slip; m) evolves by `d[[u]]/dt = [[v*]]`
//! (3.40), which every law gives as `rate = (w_a + w_b - 2 s*) / Z` per frame direction (both
//! sides keep their outgoing characteristic).

mod cohesive;
mod contact;
mod damage;
mod error;
mod registry;
mod scaled;
mod targets;

pub use cohesive::{CohesiveParams, XuNeedleman};
pub use contact::ContactParams;
pub use damage::{DamageLaw, DamageParams};
pub use error::LawError;
pub use registry::{Interfaces, Law};
pub use scaled::Contact;
pub use targets::{Mode, Targets, characteristics};
