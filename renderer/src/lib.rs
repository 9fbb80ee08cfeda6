//! A verified classic ray tracer.
//!
//! See ARCHITECTURE.md at the repository root for the bird's-eye view and invariants.

pub mod aabb;
pub mod aggregate;
pub mod bvh;
pub mod camera;
pub mod hit;
pub mod light;
pub mod material;
pub mod output;
pub mod physical;
pub mod ray;
pub mod real;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shading;
pub mod shapes;
pub mod spawn;
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
/// instruction would kill the process with SIGILL; the binaries call this first and exit
/// with this message instead.
pub fn check_cpu() -> Result<(), String> {
    #[cfg(target_arch = "x86_64")]
    {
        let missing: Vec<&str> = [
            (
                "avx2",
                cfg!(target_feature = "avx2"),
                std::arch::is_x86_feature_detected!("avx2"),
            ),
            (
                "fma",
                cfg!(target_feature = "fma"),
                std::arch::is_x86_feature_detected!("fma"),
            ),
            (
                "bmi2",
                cfg!(target_feature = "bmi2"),
                std::arch::is_x86_feature_detected!("bmi2"),
            ),
        ]
        .into_iter()
        .filter(|&(_, built, has)| built && !has)
        .map(|(name, _, _)| name)
        .collect();
        if !missing.is_empty() {
            return Err(format!(
                "this build needs the processor features {} (x86-64-v3, set in \
                 .cargo/config.toml), which this processor lacks; rebuild for it with \
                 `RUSTFLAGS= cargo build --release`",
                missing.join(", ")
            ));
        }
    }
    Ok(())
}
