//! One scene against its Mitsuba 3 references: the verdict of the statistical radiance
//! test and the geometry comparison, their metrics, the worst pixels by z, and the z
//! image, as the gate reads them ([`Checked`]).

use super::compare::{
    p_value, sidak_alpha, GeometryTest, RadianceTest, GLOBAL_Z, PIXEL_PASS_FRACTION,
};
use crate::checked::{worst_pixels, Checked, Figure, Pixel};
use crate::verdict::Verdict;
use renderer::render::Image;

/// One scene against Mitsuba.
pub struct Outcome {
    /// Scene name.
    pub scene: String,
    /// The verdict over both tests and freshness, before waivers.
    pub verdict: Verdict,
    /// The geometric comparison.
    pub geometry: Option<GeometryTest>,
    /// The statistical comparison.
    pub radiance: Option<RadianceTest>,
    /// Our render (RGB mean, AOVs, moments).
    pub ours: Image,
    /// The reference's RGB mean.
    pub reference_rgb: Option<Vec<f32>>,
    /// Seconds our render took.
    pub seconds: f64,
}

impl Outcome {
    /// A scene without references: our render alone, `Missing`.
    pub fn missing(scene: &str, ours: Image, seconds: f64) -> Outcome {
        Outcome {
            scene: scene.to_string(),
            verdict: Verdict::Missing,
            geometry: None,
            radiance: None,
            ours,
            reference_rgb: None,
            seconds,
        }
    }
}

impl Checked for Outcome {
    fn reference(&self) -> &str {
        "mitsuba"
    }

    fn catalog(&self) -> &str {
        "mitsuba"
    }

    fn scene(&self) -> &str {
        &self.scene
    }

    fn verdict(&self) -> Verdict {
        self.verdict
    }

    fn checks(&self) -> Vec<(&'static str, bool)> {
        let mut v = Vec::new();
        if let Some(r) = &self.radiance {
            v.push(("radiance", r.passed()));
        }
        if let Some(g) = &self.geometry {
            v.push(("geometry", g.passed()));
        }
        v
    }

    fn metrics(&self) -> String {
        match (&self.radiance, &self.geometry) {
            (Some(r), Some(g)) => format!(
                "radiance: {:.3} % of pixel-channels pass (need {:.2} %), global z {:.2} {:.2} {:.2} (need |z| < {}), RMSE {:.3e}; \
geometry: distance error {:.1e}, normal {:.4}°, {} failing and {} edge pixels (budget {})",
                r.pass_fraction * 100.0,
                PIXEL_PASS_FRACTION * 100.0,
                r.global_z[0],
                r.global_z[1],
                r.global_z[2],
                GLOBAL_Z,
                r.rmse,
                g.max_rel_distance,
                g.max_normal_degrees,
                g.failing,
                g.silhouette,
                g.budget
            ),
            _ => "no reference".into(),
        }
    }

    fn ours(&self) -> &Image {
        &self.ours
    }

    fn reference_rgb(&self) -> Option<&[f32]> {
        self.reference_rgb.as_deref()
    }

    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn worst(&self, n: usize) -> Vec<Pixel> {
        let (Some(r), Some(reference)) = (&self.radiance, &self.reference_rgb) else {
            return Vec::new();
        };
        let class = |k: usize| format!("z = {:.1}", r.z_max[k]);
        worst_pixels(
            self.ours.width as usize,
            &self.ours.rgb,
            reference,
            n,
            &|k| r.z_max[k],
            &class,
        )
    }

    fn worst_score(&self) -> f64 {
        self.radiance
            .as_ref()
            .map_or(0.0, |r| r.z_max.iter().copied().fold(0.0, f64::max))
    }

    fn figure(&self) -> Option<Figure> {
        let r = self.radiance.as_ref()?;
        let alpha = sidak_alpha((self.ours.width * self.ours.height) as usize);
        Some(Figure {
            name: "z",
            linear: r.z_max.iter().flat_map(|&v| [v as f32; 3]).collect(),
            png: z_image(&r.z_max, alpha),
        })
    }
}

/// A false-colour image of per-pixel z: black to white up to z = 2, orange up to the
/// Šidák threshold, red beyond it.
pub fn z_image(z: &[f64], alpha: f64) -> Vec<u8> {
    let mut out = Vec::with_capacity(z.len() * 3);
    for &v in z {
        if p_value(v) <= alpha {
            out.extend_from_slice(&[230, 0, 0]);
        } else if v > 2.0 {
            out.extend_from_slice(&[255, 160, 0]);
        } else {
            let g = (v / 2.0 * 200.0) as u8;
            out.extend_from_slice(&[g, g, g]);
        }
    }
    out
}
