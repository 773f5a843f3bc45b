//! Meshes for the unit tests.

use sdg_mesh::{Diagonal, Mesh, Rectangle};

/// A unit square of `nx` x `ny` cells (alternating diagonals), interior vertices moved by up
/// to `perturb` cells.
pub fn rectangle(nx: u32, ny: u32, perturb: f64, seed: u64) -> Mesh {
    build(1.0, nx, ny, perturb, seed)
}

/// A 4 m x 1 m strip of `nx` x `ny` cells.
pub fn strip(nx: u32, ny: u32) -> Mesh {
    build(4.0, nx, ny, 0.0, 0)
}

fn build(width: f64, nx: u32, ny: u32, perturb: f64, seed: u64) -> Mesh {
    Rectangle {
        width,
        height: 1.0,
        nx,
        ny,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb,
        seed,
    }
    .build()
    .expect("a valid rectangle")
}
