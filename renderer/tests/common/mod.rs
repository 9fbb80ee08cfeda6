//! Helpers shared by the renderer's integration tests.
#![allow(dead_code)]

use glam::DVec3;
use renderer::sampler::mix64;

/// SplitMix64: a small deterministic generator, so the tests need no `rand` crate and
/// every run draws the same cases.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.0)
    }
    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    /// An index in 0..n, from the raw bits.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    /// An index in 0..n, from a uniform number.
    pub fn below_scaled(&mut self, n: usize) -> usize {
        (self.f() * n as f64) as usize % n
    }
    /// True with probability p.
    pub fn chance(&mut self, p: f64) -> bool {
        self.f() < p
    }
    /// Each component uniform in [a, b).
    pub fn vec(&mut self, a: f64, b: f64) -> DVec3 {
        DVec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
    /// Uniform in the unit ball.
    pub fn ball(&mut self) -> DVec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            if v.length_squared() <= 1.0 {
                return v;
            }
        }
    }
    /// A ray `(origin, direction)` aimed at a random point of the unit cylinder's rims
    /// (radius 1 about y, y = ±1) from a random origin in [−4, 4)³: where the side's
    /// computed point rounds across y = ±1 and a side root meets the slab's end.
    pub fn toward_cylinder_rim(&mut self) -> (DVec3, DVec3) {
        let turn = self.range(0.0, std::f64::consts::TAU);
        let y = if self.chance(0.5) { 1.0 } else { -1.0 };
        let o = self.vec(-4.0, 4.0);
        (o, DVec3::new(turn.cos(), y, turn.sin()) - o)
    }
    /// A uniform unit vector (from the ball, rejecting lengths below 1e-2).
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.ball();
            let l = v.length();
            if l > 1e-2 {
                return v / l;
            }
        }
    }
}

pub mod extremes;
pub mod primitives;
