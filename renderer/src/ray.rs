//! Rays: `o + t·d`, with `d` deliberately left unnormalized so that `t` means the same thing
//! in world and object space.

use crate::real::{Real, Vec3};

/// A ray `o + t·d`. `d` is not normalized.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Direction (any non-zero length).
    pub d: Vec3,
}

impl Ray {
    /// A ray from `o` along `d`.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray { o, d }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: Real) -> Vec3 {
        self.o + self.d * t
    }
}
