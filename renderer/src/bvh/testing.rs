//! Test data shared by the BVH's unit tests.

use crate::aabb::Aabb;
use crate::real::{Real, Vec3};

/// Test numbers: the sampler's hash of (test, case, dimension), in [0, 1).
pub(super) fn u(case: u64, dim: u64) -> Real {
    crate::sampler::uniform(0xb7b, case, dim) as Real
}

/// `n` boxes in a 10-unit cube, each up to 1 unit a side, from test numbers
/// `first..first + n`.
pub(super) fn random_boxes(first: u64, n: usize) -> Vec<Aabb> {
    (first..first + n as u64)
        .map(|k| {
            let c = Vec3::new(u(k, 1), u(k, 2), u(k, 3)) * 10.0;
            Aabb {
                min: c,
                max: c + Vec3::new(u(k, 4), u(k, 5), u(k, 6)),
            }
        })
        .collect()
}
