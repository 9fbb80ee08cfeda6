//! Statistical comparison of a Monte Carlo render with a Mitsuba reference, and the
//! geometric comparison of AOVs with pixel-centre ray casts.
//!
//! Radiance is compared in **CIE XYZ**, because Mitsuba's `moment` integrator stores the
//! per-sample first and second moments of XYZ (src/integrators/moment.cpp). The renderer's
//! RGB mean and RGB second moments convert exactly, since XYZ is linear in RGB.
//!
//! - **Per pixel and channel**, a two-sample z-test. Mitsuba's own render tests
//!   (src/render/tests/test_renders.py) use only the reference's variance, which is right
//!   when both images come from the same estimator. Here the estimators differ, for
//!   example in how sphere lights are sampled, so each side contributes its own variance:
//!   `z = |m₁ − m₂| / √(max(v₁, 1e-4)/n₁ + max(v₂, 1e-4)/n₂)`, with Mitsuba's variance
//!   floor of 1e-4. A pixel-channel passes when its two-sided p-value exceeds the
//!   Šidák-corrected `α = 1 − 0.99^(1/pixels)`. The image passes when at least
//!   [`PIXEL_PASS_FRACTION`] of the pixel-channels pass (Mitsuba's criterion).
//! - **Per channel, over the whole image**, a global test of the mean difference against
//!   its standard error. The per-pixel test alone misses a small uniform bias: a light 2 %
//!   too bright passes every pixel (see ../shared/notes/reference-tools.md). The global z
//!   must stay below [`GLOBAL_Z`].

/// sRGB (linear, D65) to CIE XYZ, the matrix Mitsuba uses (`srgb_to_xyz`).
pub const SRGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.412453, 0.357580, 0.180423],
    [0.212671, 0.715160, 0.072169],
    [0.019334, 0.119193, 0.950227],
];

/// Fraction of pixel-channels that must pass (Mitsuba's test_renders.py).
pub const PIXEL_PASS_FRACTION: f64 = 0.9975;
/// Largest allowed |z| of an image's mean difference, per channel.
pub const GLOBAL_Z: f64 = 4.5;
/// Floor on per-sample variance (Mitsuba's test_renders.py).
pub const VARIANCE_FLOOR: f64 = 1e-4;

/// Complementary error function, with relative error below 1.2e-7 (the Chebyshev fit of
/// Numerical Recipes, `erfcc`).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Two-sided p-value of a standard normal z.
pub fn p_value(z: f64) -> f64 {
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// The Šidák-corrected per-pixel significance for an image of `pixels` pixels.
pub fn sidak_alpha(pixels: usize) -> f64 {
    1.0 - 0.99f64.powf(1.0 / pixels as f64)
}

/// A pixel estimate: the XYZ mean and per-sample variance, from `n` samples.
#[derive(Clone, Debug, Default)]
pub struct Estimate {
    /// Width and height.
    pub size: (usize, usize),
    /// XYZ mean, 3 per pixel.
    pub mean: Vec<f64>,
    /// XYZ per-sample variance, 3 per pixel.
    pub var: Vec<f64>,
    /// Samples per pixel.
    pub n: f64,
}

impl Estimate {
    /// From the renderer's RGB mean and RGB second moments
    /// (E[R²], E[G²], E[B²], E[RG], E[RB], E[GB] per pixel).
    pub fn from_rgb_moments(size: (usize, usize), rgb: &[f32], moments: &[f32], n: u32) -> Self {
        let px = size.0 * size.1;
        let (mut mean, mut var) = (Vec::with_capacity(px * 3), Vec::with_capacity(px * 3));
        for k in 0..px {
            let c = [
                rgb[3 * k] as f64,
                rgb[3 * k + 1] as f64,
                rgb[3 * k + 2] as f64,
            ];
            let m = &moments[6 * k..6 * k + 6];
            let e = |i: usize, j: usize| -> f64 {
                let idx = match (i.min(j), i.max(j)) {
                    (0, 0) => 0,
                    (1, 1) => 1,
                    (2, 2) => 2,
                    (0, 1) => 3,
                    (0, 2) => 4,
                    _ => 5,
                };
                m[idx] as f64 - c[i] * c[j]
            };
            for row in SRGB_TO_XYZ {
                mean.push(row[0] * c[0] + row[1] * c[1] + row[2] * c[2]);
                let mut v = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        v += row[i] * row[j] * e(i, j);
                    }
                }
                var.push(v.max(0.0));
            }
        }
        Estimate {
            size,
            mean,
            var,
            n: n as f64,
        }
    }
}

/// The result of the statistical test.
#[derive(Clone, Debug)]
pub struct RadianceTest {
    /// Fraction of pixel-channels whose p-value exceeds the Šidák α.
    pub pass_fraction: f64,
    /// Global z of the mean difference, per XYZ channel.
    pub global_z: [f64; 3],
    /// Root mean square difference of the XYZ means.
    pub rmse: f64,
    /// Largest per-pixel z over channels (for the difference image).
    pub z_max: Vec<f64>,
}

impl RadianceTest {
    /// Whether the render is statistically consistent with the reference.
    pub fn passed(&self) -> bool {
        self.pass_fraction >= PIXEL_PASS_FRACTION
            && self.global_z.iter().all(|z| z.abs() < GLOBAL_Z)
    }
}

/// Compares two estimates of the same image.
pub fn radiance_test(a: &Estimate, b: &Estimate) -> RadianceTest {
    assert_eq!(a.size, b.size, "image sizes differ");
    let px = a.size.0 * a.size.1;
    let alpha = sidak_alpha(px);
    let mut passed = 0usize;
    let (mut sum_d, mut sum_v) = ([0f64; 3], [0f64; 3]);
    let mut sq = 0.0;
    let mut z_max = vec![0.0; px];
    for k in 0..px {
        for c in 0..3 {
            let i = 3 * k + c;
            let d = a.mean[i] - b.mean[i];
            let se =
                (a.var[i].max(VARIANCE_FLOOR) / a.n + b.var[i].max(VARIANCE_FLOOR) / b.n).sqrt();
            let z = d.abs() / se;
            if p_value(z) > alpha {
                passed += 1;
            }
            z_max[k] = f64::max(z_max[k], z);
            sum_d[c] += d;
            sum_v[c] += a.var[i] / a.n + b.var[i] / b.n;
            sq += d * d;
        }
    }
    let global_z = [0, 1, 2].map(|c| {
        if sum_v[c] > 0.0 {
            sum_d[c] / sum_v[c].sqrt()
        } else if sum_d[c] == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    });
    RadianceTest {
        pass_fraction: passed as f64 / (px * 3) as f64,
        global_z,
        rmse: (sq / (px * 3) as f64).sqrt(),
        z_max,
    }
}

/// Tolerances of the geometric comparison (both renderers intersect in f32).
pub const GEOMETRY_REL_DISTANCE: f64 = 2e-5;
/// Largest angle between normals, in degrees.
pub const GEOMETRY_NORMAL_DEGREES: f64 = 0.01;
/// Largest allowed fraction of edge pixels in the geometric comparison.
pub const GEOMETRY_EDGE_BUDGET: f64 = 0.0025;

/// Geometry channels of one image: distance from the eye, unit normal, hit mask.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// Width and height.
    pub size: (usize, usize),
    /// Distance from the eye (0 on a miss).
    pub z: Vec<f64>,
    /// Unit normals, 3 per pixel.
    pub n: Vec<f64>,
    /// Hit mask.
    pub hit: Vec<bool>,
}

/// The result of the geometric comparison.
#[derive(Clone, Debug)]
pub struct GeometryTest {
    /// Largest relative distance error over pixels both hit.
    pub max_rel_distance: f64,
    /// Largest normal angle (degrees) over pixels both hit.
    pub max_normal_degrees: f64,
    /// Pixels outside tolerance whose surface (hit and normal) a neighbouring reference
    /// pixel hit: the ray fell on the other side of an edge.
    pub silhouette: usize,
    /// Other pixels outside tolerance.
    pub failing: usize,
    /// Edge-pixel budget ([`GEOMETRY_EDGE_BUDGET`] of the pixels).
    pub budget: usize,
}

impl GeometryTest {
    /// Whether the geometry agrees.
    pub fn passed(&self) -> bool {
        self.failing == 0 && self.silhouette <= self.budget
    }
}

/// The angle in degrees between normal `i` of `a` and normal `j` of `b`, computed as
/// `atan2(|a×b|, a·b)`. (`acos(a·b)` is ill-conditioned near 0: two f32-stored unit
/// normals 4e-7 rad apart read as 0.02° through it.)
fn angle(a: &Geometry, i: usize, b: &Geometry, j: usize) -> f64 {
    let u = glam::DVec3::new(a.n[3 * i], a.n[3 * i + 1], a.n[3 * i + 2]);
    let v = glam::DVec3::new(b.n[3 * j], b.n[3 * j + 1], b.n[3 * j + 2]);
    u.cross(v).length().atan2(u.dot(v)).to_degrees()
}

/// Whether pixel `i` of `a` hit the same surface as pixel `j` of `b`: both miss, or both
/// hit with normals within tolerance (distances differ from pixel to pixel).
fn same_surface(a: &Geometry, i: usize, b: &Geometry, j: usize) -> bool {
    if a.hit[i] != b.hit[j] {
        return false;
    }
    !a.hit[i] || angle(a, i, b, j) <= GEOMETRY_NORMAL_DEGREES
}

fn agrees(a: &Geometry, i: usize, b: &Geometry, j: usize) -> (bool, f64, f64) {
    if a.hit[i] != b.hit[j] {
        return (false, 0.0, 0.0);
    }
    if !a.hit[i] {
        return (true, 0.0, 0.0);
    }
    let rel = (a.z[i] - b.z[j]).abs() / b.z[j].max(1e-30);
    let deg = angle(a, i, b, j);
    (
        rel <= GEOMETRY_REL_DISTANCE && deg <= GEOMETRY_NORMAL_DEGREES,
        rel,
        deg,
    )
}

/// Compares our pixel-centre geometry (`a`) with the reference (`b`).
pub fn geometry_test(a: &Geometry, b: &Geometry) -> GeometryTest {
    let (w, h) = a.size;
    let (mut max_rel, mut max_deg, mut silhouette, mut failing) = (0f64, 0f64, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (ok, rel, deg) = agrees(a, i, b, i);
            if ok {
                max_rel = max_rel.max(rel);
                max_deg = max_deg.max(deg);
                continue;
            }
            // An edge pixel: its ray fell on the other side of an edge, onto a surface that
            // a neighbouring reference ray hit.
            let near = (y.saturating_sub(1)..(y + 2).min(h)).any(|yy| {
                (x.saturating_sub(1)..(x + 2).min(w))
                    .any(|xx| (yy, xx) != (y, x) && same_surface(a, i, b, yy * w + xx))
            });
            if near {
                silhouette += 1;
            } else {
                failing += 1;
            }
        }
    }
    GeometryTest {
        max_rel_distance: max_rel,
        max_normal_degrees: max_deg,
        silhouette,
        failing,
        budget: ((w * h) as f64 * GEOMETRY_EDGE_BUDGET).floor() as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_matches_known_values() {
        for (x, want) in [
            (0.0, 1.0),
            (0.5, 0.479_500_122),
            (1.0, 0.157_299_207),
            (2.0, 0.004_677_735),
            (3.0, 2.209_05e-5),
            (-1.0, 1.842_700_793),
        ] {
            assert!(
                (erfc(x) - want).abs() <= 2e-7 * want.max(1e-3),
                "erfc({x}) = {} vs {want}",
                erfc(x)
            );
        }
        // The Šidák threshold for a 48×36 image is near z = 4.54.
        let a = sidak_alpha(48 * 36);
        assert!(p_value(4.5) > a && p_value(4.6) < a);
    }

    #[test]
    fn the_radiance_rmse_is_over_every_channel_of_every_pixel() {
        // 2 × 2 pixels, one channel of one pixel off by 0.6: RMSE = 0.6 / sqrt(12).
        let est = |mean: Vec<f64>| Estimate {
            size: (2, 2),
            var: vec![1.0; 12],
            mean,
            n: 16.0,
        };
        let mut off = vec![0.5; 12];
        off[7] += 0.6;
        let t = radiance_test(&est(off), &est(vec![0.5; 12]));
        let want = 0.6 / 12f64.sqrt();
        assert!(
            (t.rmse - want).abs() < 1e-12,
            "rmse {} (want {want}: the squared differences are averaged over 4 pixels × 3 \
             channels; radiance_test in conformance/src/mitsuba/compare.rs)",
            t.rmse
        );
    }

    #[test]
    fn the_xyz_variance_comes_from_the_rgb_covariance() {
        // One pixel with a known RGB mean and covariance: the XYZ variance of each row is
        // row · Cov · rowᵀ.
        let c = [0.2f64, 0.4, 0.6];
        let cov = [
            [0.01, 0.005, 0.001],
            [0.005, 0.02, 0.002],
            [0.001, 0.002, 0.03],
        ];
        let m = [
            c[0] * c[0] + cov[0][0],
            c[1] * c[1] + cov[1][1],
            c[2] * c[2] + cov[2][2],
            c[0] * c[1] + cov[0][1],
            c[0] * c[2] + cov[0][2],
            c[1] * c[2] + cov[1][2],
        ]
        .map(|v| v as f32);
        let e = Estimate::from_rgb_moments((1, 1), &c.map(|v| v as f32), &m, 16);
        for (k, row) in SRGB_TO_XYZ.iter().enumerate() {
            let want: f64 = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| row[i] * row[j] * cov[i][j])
                .sum();
            assert!(
                (e.var[k] - want).abs() < 1e-6,
                "row {k}: variance {} != {want}",
                e.var[k]
            );
            let mean: f64 = (0..3).map(|i| row[i] * c[i]).sum();
            assert!((e.mean[k] - mean).abs() < 1e-6);
        }
        assert_eq!(e.n, 16.0);
    }

    #[test]
    fn an_edge_pixel_at_the_image_border_is_matched_by_its_neighbour() {
        // Our first pixel's ray hit the surface the reference's second pixel hit (at the
        // border of the image, along a row and along a column): an edge pixel, not failing.
        for (w, h) in [(3, 1), (1, 3)] {
            let geo = |z: [f64; 3]| Geometry {
                size: (w, h),
                z: z.to_vec(),
                n: [0.0, 0.0, 1.0].repeat(3),
                hit: vec![true; 3],
            };
            let t = geometry_test(&geo([2.0, 2.0, 2.0]), &geo([1.0, 2.0, 2.0]));
            assert_eq!((t.silhouette, t.failing), (1, 0), "{w}x{h}");
        }
    }
}
