//! Eight lanes of three-vectors (f32x8 each), and the per-lane random numbers.
use wide::*;

/// Eight 3-vectors, one a lane.
#[derive(Clone, Copy)]
pub struct V {
    pub x: f32x8,
    pub y: f32x8,
    pub z: f32x8,
}

impl V {
    /// The same vector in every lane.
    pub fn splat(x: f32, y: f32, z: f32) -> V {
        V { x: f32x8::splat(x), y: f32x8::splat(y), z: f32x8::splat(z) }
    }
    pub fn dot(self, o: V) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    pub fn add(self, o: V) -> V {
        V { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
    pub fn sub(self, o: V) -> V {
        V { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
    pub fn mul(self, k: f32x8) -> V {
        V { x: self.x * k, y: self.y * k, z: self.z * k }
    }
    pub fn normalize(self) -> V {
        self.mul(f32x8::ONE / self.dot(self).sqrt())
    }
    /// `a` where `mask` is set, else `b`, lane by lane.
    pub fn blend(mask: f32x8, a: V, b: V) -> V {
        V { x: mask.blend(a.x, b.x), y: mask.blend(a.y, b.y), z: mask.blend(a.z, b.z) }
    }
}

/// A 32-bit integer hash (lowbias32), lane by lane.
fn hash(mut x: u32x8) -> u32x8 {
    x = x ^ (x >> 16);
    x = x * u32x8::splat(0x7feb_352d);
    x = x ^ (x >> 15);
    x = x * u32x8::splat(0x846c_a68b);
    x ^ (x >> 16)
}

/// Independent uniform numbers in [0, 1): dimension `dim` of each lane's sample `key`.
pub fn uniform(key: u32x8, dim: u32) -> f32x8 {
    let h = hash(key ^ u32x8::splat(dim.wrapping_mul(0x27d4_eb2f)));
    let i: i32x8 = bytemuck::cast(h >> 8);
    f32x8::from_i32x8(i) * f32x8::splat(1.0 / 16_777_216.0)
}
