//! Sums of Kronecker products, the blocks of the patch system.

use faer::Accum;

use crate::system::{MAX_FIELDS, Matrix};

/// Adds the sum of Kronecker products `sum_t scalar_t (x) block_t` to the column-major `m x m`
/// matrix `target` (`Accum::Add`), or stores it there (`Accum::Replace`, every entry written):
/// entry `(k, l)` of each `n x n` row-major `scalar_t` scales `block_t` at rows `k fields..`,
/// columns `l fields..`, with `m = n fields`. The blocks are combined per `(k, l)` first, so
/// `target` is written once whatever the number of terms.
pub(super) fn kron_sum(
    target: &mut [f64],
    accum: Accum,
    m: usize,
    n: usize,
    fields: usize,
    terms: &[(&[f64], Matrix)],
) {
    for l in 0..n {
        for k in 0..n {
            let mut sum = [[0.0; MAX_FIELDS]; MAX_FIELDS];
            for (scalar, block) in terms {
                let s = scalar[k * n + l];
                for (row, b) in sum.iter_mut().zip(block) {
                    for (x, y) in row.iter_mut().zip(b) {
                        *x += s * y;
                    }
                }
            }
            for (b, col) in (l * fields..).take(fields).enumerate() {
                let column = &mut target[col * m + k * fields..][..fields];
                let values = column.iter_mut().zip(&sum);
                match accum {
                    Accum::Add => values.for_each(|(t, row)| *t += row[b]),
                    Accum::Replace => values.for_each(|(t, row)| *t = row[b]),
                }
            }
        }
    }
}
