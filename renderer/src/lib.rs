//! A verified classic ray tracer.
//!
//! See ARCHITECTURE.md at the repository root for the bird's-eye view and invariants.

pub mod aabb;
pub mod adaptive;
pub mod aggregate;
pub mod bvh;
pub mod camera;

pub mod hit;
pub mod image;
pub mod light;
pub mod material;
pub mod output;
pub mod pages;
pub mod physical;
pub mod progress;
pub mod ray;
pub mod real;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shading;
pub mod shapes;
pub mod spawn;
pub mod suggest;
pub mod transform;

pub use aggregate::Shape;
pub use aggregate::{Aggregate, Instance};
pub use camera::{Camera, ViewingModel, Window};
pub use hit::Hit;
pub use ray::Ray;
pub use real::{Real, Vec3};
pub use transform::{Affine64, Transform};

/// Checks that this processor has the instruction-set features the build was compiled for
/// (x86-64-v3 on x86-64 Linux: `.cargo/config.toml`). Without them the first AVX2
/// instruction would kill the process with SIGILL; the binaries call this first thing in
/// `main` and exit with this message instead.
///
/// It reads CPUID itself: `is_x86_feature_detected!` answers "yes" without asking the
/// processor for any feature the build enables. It checks the features x86-64-v3 adds
/// (AVX, AVX2, FMA, F16C, MOVBE, BMI1, BMI2, LZCNT) and that the operating system saves
/// the vector registers (OSXSAVE). The message is a constant and is printed by the
/// standard library, which is compiled for the x86-64 baseline; the check itself is a few
/// integer tests.
pub fn check_cpu() -> Result<(), &'static str> {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        use std::arch::x86_64::{__cpuid, __cpuid_count};
        let ok = has_x86_64_v3(
            [__cpuid(0).eax, __cpuid(0x8000_0000).eax],
            __cpuid(1).ecx,
            __cpuid_count(7, 0).ebx,
            __cpuid(0x8000_0001).ecx,
        );
        if !ok {
            return Err(
                "this build needs an x86-64-v3 processor (AVX2, FMA, BMI1/2, LZCNT, \
                        MOVBE, F16C: set in .cargo/config.toml), which this one is not; \
                        rebuild for it with `RUSTFLAGS= cargo build --release`",
            );
        }
    }
    Ok(())
}

/// Whether CPUID's answers name every feature x86-64-v3 adds: `max` holds the highest
/// basic and extended leaves, then leaf 1's ECX, leaf 7's EBX and leaf 0x8000_0001's ECX.
pub fn has_x86_64_v3(max: [u32; 2], leaf1_ecx: u32, leaf7_ebx: u32, ext_ecx: u32) -> bool {
    let bit = |word: u32, b: u32| word >> b & 1 == 1;
    max[0] >= 7
        && max[1] >= 0x8000_0001
        // FMA, MOVBE, OSXSAVE, AVX, F16C
        && [12, 22, 27, 28, 29].iter().all(|&b| bit(leaf1_ecx, b))
        // BMI1, AVX2, BMI2
        && [3, 5, 8].iter().all(|&b| bit(leaf7_ebx, b))
        // LZCNT
        && bit(ext_ecx, 5)
}

#[cfg(test)]
mod tests {
    use super::has_x86_64_v3;

    /// The development machine's CPUID answers (an AMD EPYC) name every feature; clearing
    /// any one of them, or a leaf that is not there, must refuse.
    #[test]
    fn x86_64_v3_needs_every_feature() {
        let (max, l1, l7, ext) = ([0x10, 0x8000_0021], 0xfffa_3203, 0xf1bf_07ab, 0x0040_03f3);
        assert!(has_x86_64_v3(max, l1, l7, ext));
        for b in [12, 22, 27, 28, 29] {
            assert!(
                !has_x86_64_v3(max, l1 & !(1 << b), l7, ext),
                "leaf 1 ECX bit {b}"
            );
        }
        for b in [3, 5, 8] {
            assert!(
                !has_x86_64_v3(max, l1, l7 & !(1 << b), ext),
                "leaf 7 EBX bit {b}"
            );
        }
        assert!(!has_x86_64_v3(max, l1, l7, ext & !(1 << 5)), "LZCNT");
        assert!(!has_x86_64_v3([6, max[1]], l1, l7, ext), "no leaf 7");
        assert!(
            !has_x86_64_v3([max[0], 0x8000_0000], l1, l7, ext),
            "no extended leaf 1"
        );
    }
}
