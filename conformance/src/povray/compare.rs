//! Comparing a render with a deterministic pixel-centre reference.
//!
//! POV-Ray writes EXR as half floats, so a reference value r is only known to within its
//! rounding error, `2⁻¹¹·|r|` (half has an 11-bit significand). The per-channel tolerance is
//!
//! ```text
//! tol(r) = 1.05 · 2⁻¹¹ · |r| + 1e-6
//! ```
//!
//! The 5 % margin covers this renderer's own f32 rounding: measured over the catalog,
//! agreeing pixels never exceed 1.046× the half bound. The absolute floor covers values
//! below the smallest normal half.
//!
//! A pixel outside tolerance is **excused** (a silhouette pixel) only when geometry explains
//! it: our own image takes the reference's value a tiny distance from the pixel centre. The
//! comparison traces the pixel again, through the image's own render path, at sub-pixel
//! positions in eight directions, and excuses it when, along one direction, the reference
//! value lies (channel by channel, ± tol) between our value at the centre and our value at
//! the moved sample, in one of two ways:
//!
//! - **within [`EPSILON`]** (1e-3 pixel): rounding moved the two renderers' samples apart
//!   by less than that, on a surface whose shading is steep (seen at a grazing angle, or
//!   far from the eye), or across an edge that passes that close to the centre;
//! - **within [`EDGE_EPSILON`]** (1e-2 pixel), and only if a **discontinuity** lies on that
//!   segment (bisection finds a jump beyond tolerance across an interval of 6e-10 pixel):
//!   an object's outline, a shadow edge, or an edge seen in a mirror or through glass,
//!   which the two renderers place on different sides of the centre or which the reference
//!   resolves with a value between the two sides (POV-Ray does, in slivers a few
//!   thousandths of a pixel wide along shadows cast through glass).
//!
//! A smooth shading error cannot be excused: moving the sample by `EPSILON` changes a
//! smooth value by `EPSILON` times its gradient, so an error larger than that (plus the
//! tolerance) is bracketed by no direction, and the wider radius needs a jump. Every other
//! pixel outside tolerance is **failing**; one fails the comparison, and the excused pixels
//! must stay within [`SILHOUETTE_BUDGET`].

/// Relative tolerance: the half-float rounding bound with a 5 % margin.
pub const REL_TOL: f64 = 1.05 / 2048.0;
/// Absolute floor of the tolerance.
pub const ABS_TOL: f64 = 1e-6;
/// Distance, in pixels, of the re-traced samples that may explain a difference anywhere.
pub const EPSILON: f64 = 1e-3;
/// Distance, in pixels, of the re-traced samples that may explain a difference across a
/// discontinuity.
pub const EDGE_EPSILON: f64 = 1e-2;
/// Largest allowed fraction of excused (silhouette) pixels: 3 of the 6,912 pixels of a
/// 96×72 image. The catalog measures at most 1 (conformance/docs/tolerances.md).
pub const SILHOUETTE_BUDGET: f64 = 0.0005;

/// Bisection steps that look for a discontinuity on a segment of `EDGE_EPSILON`: they
/// narrow it to 1e-2 / 2²⁴ ≈ 6e-10 pixel, across which smooth shading cannot change
/// beyond tolerance.
const BISECTIONS: u32 = 24;

/// The eight directions of the re-traced samples (unit vectors, 45° apart): a straight edge
/// within 0.92 times the radius of the centre is crossed by at least one of them.
const DIRECTIONS: [(f64, f64); 8] = {
    const D: f64 = std::f64::consts::FRAC_1_SQRT_2;
    [
        (1.0, 0.0),
        (D, D),
        (0.0, 1.0),
        (-D, D),
        (-1.0, 0.0),
        (-D, -D),
        (0.0, -1.0),
        (D, -D),
    ]
};

/// The tolerance for a reference value.
#[inline]
pub fn tol(r: f64) -> f64 {
    REL_TOL * r.abs() + ABS_TOL
}

/// One camera sample traced again at a continuous pixel position (x to the right, y down,
/// pixel (i, j)'s centre at (i + ½, j + ½)), through the same render path as the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The sample's value, with non-finite channels written as 0 as in the image.
    pub rgb: [f32; 3],
    /// Object id of the camera ray's first hit (0 for the background).
    pub object: u32,
    /// Whether that first surface reflects or transmits light.
    pub secondary: bool,
}

/// How many pixels were excused, and why. The kind is read from the camera ray's first
/// hit at the centre and at the moved sample whose value brackets the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Excused {
    /// The first hit changes object (or hits and misses): an object's outline.
    pub outline: usize,
    /// The same reflecting or transparent surface: an edge seen in it or through it (or
    /// a shadow edge on it).
    pub seen: usize,
    /// The same opaque, non-reflecting surface: a shadow edge, or shading steep enough
    /// that a shift of less than [`EPSILON`] changes it beyond tolerance.
    pub surface: usize,
}

impl Excused {
    /// All excused pixels.
    pub fn total(&self) -> usize {
        self.outline + self.seen + self.surface
    }
}

impl std::fmt::Display for Excused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} outline, {} seen in a mirror or through glass, {} shadow or steep shading",
            self.outline, self.seen, self.surface
        )
    }
}

/// What a comparison found.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Width and height.
    pub size: (usize, usize),
    /// Largest absolute channel difference.
    pub max_abs: f64,
    /// Mean absolute channel difference.
    pub mean_abs: f64,
    /// Root mean square channel difference.
    pub rmse: f64,
    /// Pixels outside tolerance that no discontinuity excuses.
    pub failing: usize,
    /// Of the failing pixels, those whose centre the re-trace did not reproduce bit for
    /// bit: a harness error (the re-trace must follow the image's render path).
    pub unreproduced: usize,
    /// Excused (silhouette) pixels: `excused.total()`.
    pub silhouette: usize,
    /// The excused pixels by kind.
    pub excused: Excused,
    /// Per pixel: 0 within tolerance, 1 excused (silhouette), 2 failing.
    pub class: Vec<u8>,
}

impl Comparison {
    /// The silhouette budget in pixels for this image size.
    pub fn budget(&self) -> usize {
        ((self.size.0 * self.size.1) as f64 * SILHOUETTE_BUDGET).floor() as usize
    }

    /// Whether the render agrees with the reference.
    pub fn passed(&self) -> bool {
        self.failing == 0 && self.silhouette <= self.budget()
    }
}

/// Whether a value matches the reference in every channel.
fn within(a: [f64; 3], r: [f64; 3]) -> bool {
    (0..3).all(|c| (a[c] - r[c]).abs() <= tol(r[c]))
}

/// Whether the reference lies between `a` and `b` (± tol) in every channel.
fn between(a: [f64; 3], b: [f64; 3], r: [f64; 3]) -> bool {
    (0..3).all(|c| a[c].min(b[c]) - tol(r[c]) <= r[c] && r[c] <= a[c].max(b[c]) + tol(r[c]))
}

fn wide(v: [f32; 3]) -> [f64; 3] {
    v.map(|x| x as f64)
}

/// Compares RGB images (3 floats per pixel, row-major, top row first). `trace` re-traces
/// one sample of `ours` at a continuous pixel position; it is called only for pixels
/// outside tolerance.
pub fn compare(
    ours: &[f32],
    reference: &[f32],
    width: usize,
    height: usize,
    trace: &dyn Fn(f64, f64) -> Sample,
) -> Comparison {
    compare_with(ours, reference, width, height, trace, EPSILON, EDGE_EPSILON)
}

/// [`compare`] with other radii than [`EPSILON`] and [`EDGE_EPSILON`] (for measuring how
/// far from the centre the catalog's differences are explained).
pub fn compare_with(
    ours: &[f32],
    reference: &[f32],
    width: usize,
    height: usize,
    trace: &dyn Fn(f64, f64) -> Sample,
    epsilon: f64,
    edge_epsilon: f64,
) -> Comparison {
    assert_eq!(ours.len(), width * height * 3, "image size");
    assert_eq!(reference.len(), width * height * 3, "reference size");
    let px = |img: &[f32], k: usize| [0, 1, 2].map(|c| img[3 * k + c]);
    let (mut max_abs, mut sum, mut sum2) = (0f64, 0f64, 0f64);
    let mut class = vec![0u8; width * height];
    let (mut failing, mut unreproduced) = (0, 0);
    let mut excused = Excused::default();
    for y in 0..height {
        for x in 0..width {
            let k = y * width + x;
            let (a, r) = (px(ours, k), wide(px(reference, k)));
            for c in 0..3 {
                let d = (a[c] as f64 - r[c]).abs();
                max_abs = max_abs.max(d);
                sum += d;
                sum2 += d * d;
            }
            if within(wide(a), r) {
                continue;
            }
            let at = Centre {
                x: x as f64 + 0.5,
                y: y as f64 + 0.5,
                value: wide(a),
                reference: r,
            };
            let centre = trace(at.x, at.y);
            let explained = if centre.rgb == a {
                at.explain(trace, epsilon, edge_epsilon)
            } else {
                unreproduced += 1;
                None
            };
            class[k] = match explained {
                Some(s) if s.object != centre.object => {
                    excused.outline += 1;
                    1
                }
                Some(_) if centre.secondary => {
                    excused.seen += 1;
                    1
                }
                Some(_) => {
                    excused.surface += 1;
                    1
                }
                None => {
                    failing += 1;
                    2
                }
            };
        }
    }
    let n = (width * height * 3) as f64;
    Comparison {
        size: (width, height),
        max_abs,
        mean_abs: sum / n,
        rmse: (sum2 / n).sqrt(),
        failing,
        unreproduced,
        silhouette: excused.total(),
        excused,
        class,
    }
}

/// A pixel outside tolerance: its centre, our value there and the reference's.
struct Centre {
    x: f64,
    y: f64,
    value: [f64; 3],
    reference: [f64; 3],
}

impl Centre {
    /// The moved sample that explains the difference, if any (see the module docs).
    fn explain(
        &self,
        trace: &dyn Fn(f64, f64) -> Sample,
        epsilon: f64,
        edge_epsilon: f64,
    ) -> Option<Sample> {
        let at = |d: (f64, f64), t: f64| trace(self.x + t * d.0, self.y + t * d.1);
        let brackets = |s: &Sample| between(self.value, wide(s.rgb), self.reference);
        DIRECTIONS
            .iter()
            .map(|&d| at(d, epsilon))
            .find(brackets)
            .or_else(|| {
                DIRECTIONS.iter().find_map(|&d| {
                    let s = at(d, edge_epsilon);
                    (brackets(&s) && self.jumps(&at, d, edge_epsilon, wide(s.rgb))).then_some(s)
                })
            })
    }

    /// Whether our value jumps beyond tolerance somewhere on the segment from the centre
    /// to `end` (at distance `len` along `d`, with value `far`): bisection keeps the half
    /// that changes more, until smooth shading could not change across it.
    fn jumps(
        &self,
        at: &dyn Fn((f64, f64), f64) -> Sample,
        d: (f64, f64),
        len: f64,
        far: [f64; 3],
    ) -> bool {
        let change =
            |p: [f64; 3], q: [f64; 3]| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f64::max);
        let (mut lo, mut hi) = ((0.0, self.value), (len, far));
        for _ in 0..BISECTIONS {
            let t = 0.5 * (lo.0 + hi.0);
            let mid = (t, wide(at(d, t).rgb));
            if change(lo.1, mid.1) >= change(mid.1, hi.1) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        (0..3).any(|c| (lo.1[c] - hi.1[c]).abs() > tol(self.reference[c]))
    }
}

/// The largest channel error of pixel `k`, in units of [`tol`].
pub fn error_in_tolerances(ours: &[f32], reference: &[f32], k: usize) -> f64 {
    (0..3)
        .map(|c| {
            let r = reference[3 * k + c] as f64;
            (ours[3 * k + c] as f64 - r).abs() / tol(r)
        })
        .fold(0.0, f64::max)
}

/// A false-colour difference image (8-bit RGB): the reference's luminance dimmed to grey
/// where the pixel agrees, blue for pixels excused by geometry, and for failing pixels a
/// colour that encodes the error relative to the tolerance on a log scale: yellow at 1×,
/// orange-red at 30×, magenta at 1000× and beyond (the report's legend).
pub fn diff_image(cmp: &Comparison, ours: &[f32], reference: &[f32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(cmp.class.len() * 3);
    for (k, &c) in cmp.class.iter().enumerate() {
        let lum = (0.2126 * reference[3 * k]
            + 0.7152 * reference[3 * k + 1]
            + 0.0722 * reference[3 * k + 2])
            .clamp(0.0, 1.0);
        match c {
            0 => {
                let g = (lum * 90.0) as u8;
                out.extend_from_slice(&[g, g, g]);
            }
            1 => out.extend_from_slice(&[0, 160, 255]),
            _ => {
                let err = (0..3)
                    .map(|i| {
                        let r = reference[3 * k + i] as f64;
                        (ours[3 * k + i] as f64 - r).abs() / tol(r)
                    })
                    .fold(1.0, f64::max);
                out.extend_from_slice(&error_colour(err));
            }
        }
    }
    out
}

/// The colour of an error of `e` tolerances (e ≥ 1): yellow (255, 255, 0) at 1, through
/// (255, 90, 0) at 10^1.5, to magenta (200, 0, 200) at 1000 and beyond.
pub fn error_colour(e: f64) -> [u8; 3] {
    let t = (e.max(1.0).log10() / 3.0).min(1.0);
    let lerp = |a: f64, b: f64, u: f64| (a + (b - a) * u).round() as u8;
    if t < 0.5 {
        let u = t / 0.5;
        [255, lerp(255.0, 90.0, u), 0]
    } else {
        let u = (t - 0.5) / 0.5;
        [
            lerp(255.0, 200.0, u),
            lerp(90.0, 0.0, u),
            lerp(0.0, 200.0, u),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 24;
    const H: usize = 8;

    /// Samples a continuous image at the pixel centres.
    fn at_centres(f: &dyn Fn(f64, f64) -> Sample) -> Vec<f32> {
        let mut v = Vec::with_capacity(W * H * 3);
        for y in 0..H {
            for x in 0..W {
                v.extend_from_slice(&f(x as f64 + 0.5, y as f64 + 0.5).rgb);
            }
        }
        v
    }

    fn grey(v: f64, object: u32) -> Sample {
        Sample {
            rgb: [v as f32, (0.8 * v) as f32, (0.5 * v) as f32],
            object,
            secondary: false,
        }
    }

    /// Two objects meeting at the vertical line x = `edge`.
    fn step(edge: f64) -> impl Fn(f64, f64) -> Sample {
        move |x, _| if x < edge { grey(0.3, 1) } else { grey(0.6, 2) }
    }

    /// Compares `ours` (a continuous image, traced again by the comparison) with
    /// `reference` (sampled at pixel centres).
    fn cmp(
        ours: &dyn Fn(f64, f64) -> Sample,
        reference: &dyn Fn(f64, f64) -> Sample,
    ) -> Comparison {
        compare(&at_centres(ours), &at_centres(reference), W, H, ours)
    }

    #[test]
    fn identical_images_pass_with_zero_metrics() {
        let f = |x: f64, y: f64| grey(0.1 + 0.01 * x + 0.02 * y, 1);
        let c = cmp(&f, &f);
        assert!(c.passed());
        assert_eq!((c.failing, c.silhouette, c.unreproduced), (0, 0, 0));
        assert_eq!((c.max_abs, c.mean_abs, c.rmse), (0.0, 0.0, 0.0));
        assert_eq!(c.class, vec![0; W * H]);
        assert_eq!(c.size, (W, H));
    }

    #[test]
    fn metrics_and_the_tolerance_edge() {
        // One pixel 1e-3 too bright in its first channel, on a value of 0.5: outside the
        // tolerance of 2.57e-4, on a flat image, so it fails.
        let f = |_: f64, _: f64| grey(0.5, 1);
        let g = |x: f64, y: f64| {
            let mut s = grey(0.5, 1);
            if (x - 3.5).abs() < 0.4 && (y - 2.5).abs() < 0.4 {
                s.rgb[0] += 1e-3;
            }
            s
        };
        let c = cmp(&g, &f);
        assert_eq!((c.failing, c.silhouette), (1, 0));
        assert!(!c.passed());
        assert_eq!(c.class[2 * W + 3], 2);
        let d = (0.5f32 + 1e-3) as f64 - 0.5;
        assert!((c.max_abs - d).abs() < 1e-12);
        assert!((c.mean_abs - d / (W * H * 3) as f64).abs() < 1e-12);
        assert!((c.rmse - (d * d / (W * H * 3) as f64).sqrt()).abs() < 1e-12);
        // Within tolerance (2e-4 < 2.57e-4) it passes.
        let h = |x: f64, y: f64| {
            let mut s = grey(0.5, 1);
            if (x - 3.5).abs() < 0.4 && (y - 2.5).abs() < 0.4 {
                s.rgb[0] += 2e-4;
            }
            s
        };
        let c = cmp(&h, &f);
        assert!(c.passed() && c.failing == 0 && c.silhouette == 0);
        assert_eq!(tol(0.5), REL_TOL * 0.5 + ABS_TOL);
        assert_eq!(tol(-0.5), tol(0.5));
    }

    #[test]
    fn an_edge_within_epsilon_is_an_outline() {
        // Our edge just right of pixel 10's centre, the reference's just left of it.
        let c = cmp(&step(10.5 + 4e-4), &step(10.5 - 4e-4));
        assert_eq!((c.failing, c.silhouette), (0, H));
        assert_eq!(c.excused.outline, H);
        assert_eq!(c.excused.total(), H);
        assert_eq!(c.class[10], 1);
        assert_eq!(c.budget(), 0, "0.05 % of 192 pixels");
        assert!(!c.passed());
    }

    #[test]
    fn an_edge_within_the_edge_radius_is_excused_only_across_a_jump() {
        // 5e-3 from the centre: beyond EPSILON, within EDGE_EPSILON.
        let c = cmp(&step(10.5 + 5e-3), &step(10.5 - 5e-3));
        assert_eq!((c.failing, c.excused.outline), (0, H));
        // The reference resolves the edge with a value between the two sides (POV-Ray's
        // slivers): still excused.
        let sliver = |x: f64, y: f64| {
            if (x - 10.5).abs() < 2e-3 {
                grey(0.45, 2)
            } else {
                step(10.5)(x, y)
            }
        };
        let c = cmp(&step(10.5 + 5e-3), &sliver);
        assert_eq!((c.failing, c.excused.outline), (0, H));
        // 2e-2 away: failing.
        let c = cmp(&step(10.5 + 2e-2), &step(10.5 - 2e-2));
        assert_eq!((c.failing, c.silhouette), (H, 0));
        assert_eq!(c.class[10], 2);
    }

    #[test]
    fn steep_smooth_shading_is_excused_only_within_epsilon() {
        // Gradient 1 per pixel; the reference is our image shifted by 5e-4 pixel.
        let ours = |x: f64, _: f64| grey(0.2 + 0.01 * x.fract(), 1);
        let steep = |x: f64, _: f64| grey(0.2 + (x - 10.0).clamp(0.0, 1.0) * 0.5, 1);
        let shifted = |x: f64, y: f64| steep(x + 5e-4, y);
        let c = cmp(&steep, &shifted);
        assert_eq!((c.failing, c.silhouette, c.excused.surface), (0, H, H));
        // Shifted by 5e-3: the difference is bracketed within EDGE_EPSILON, but there is no
        // jump, so it fails.
        let far = |x: f64, y: f64| steep(x + 5e-3, y);
        let c = cmp(&steep, &far);
        assert_eq!((c.failing, c.silhouette), (H, 0));
        // A smooth error on gentle shading fails.
        let off = |x: f64, y: f64| {
            let mut s = ours(x, y);
            s.rgb = s.rgb.map(|v| v * 1.002);
            s
        };
        let c = cmp(&off, &ours);
        assert_eq!(c.failing, W * H);
    }

    /// [`step`] on one object, reflecting or transmitting or not.
    fn on_one_object(edge: f64, secondary: bool) -> impl Fn(f64, f64) -> Sample {
        move |x, y| Sample {
            secondary,
            object: 3,
            ..step(edge)(x, y)
        }
    }

    #[test]
    fn edges_seen_in_glass_and_on_one_surface_are_told_apart() {
        let (ours, reference) = (10.5 + 4e-4, 10.5 - 4e-4);
        let c = cmp(&on_one_object(ours, true), &on_one_object(reference, true));
        assert_eq!(
            (c.excused.seen, c.excused.outline, c.excused.surface),
            (H, 0, 0)
        );
        let c = cmp(
            &on_one_object(ours, false),
            &on_one_object(reference, false),
        );
        assert_eq!(
            (c.excused.surface, c.excused.outline, c.excused.seen),
            (H, 0, 0)
        );
        assert!(c.excused.to_string().contains(&format!("{H} shadow")));
    }

    #[test]
    fn a_retrace_that_does_not_reproduce_the_image_is_failing() {
        let image = step(10.5 + 4e-4);
        let wrong = step(10.5 - 4e-4);
        let c = compare(&at_centres(&image), &at_centres(&wrong), W, H, &|x, y| {
            grey(0.61, 2 + (x + y) as u32)
        });
        assert_eq!((c.failing, c.unreproduced, c.silhouette), (H, H, 0));
    }

    #[test]
    fn the_budget_bounds_excused_pixels() {
        // 200×100 = 20,000 pixels: a budget of 10.
        let (w, h) = (200, 100);
        let edge = |n: usize| {
            move |x: f64, y: f64| {
                let on = (y as usize) < n && x > 50.5 - 4e-4;
                grey(if on || x > 51.0 { 0.6 } else { 0.3 }, 1)
            }
        };
        let ours = |x: f64, _: f64| grey(if x > 50.5 + 4e-4 { 0.6 } else { 0.3 }, 1);
        let run = |n: usize| {
            let r = edge(n);
            let mut img = Vec::new();
            let mut refr = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                    img.extend_from_slice(&ours(cx, cy).rgb);
                    refr.extend_from_slice(&r(cx, cy).rgb);
                }
            }
            compare(&img, &refr, w, h, &ours)
        };
        let c = run(10);
        assert_eq!((c.budget(), c.silhouette, c.failing), (10, 10, 0));
        assert!(c.passed());
        let c = run(11);
        assert_eq!((c.silhouette, c.failing), (11, 0));
        assert!(!c.passed());
    }

    #[test]
    fn the_difference_image_colours_each_class() {
        let c = cmp(&step(10.5 + 2e-2), &step(10.5 - 2e-2));
        let ours = at_centres(&step(10.5 + 2e-2));
        let reference = at_centres(&step(10.5 - 2e-2));
        let img = diff_image(&c, &ours, &reference);
        assert_eq!(img.len(), W * H * 3);
        // Error 0.3 on a reference of 0.6 is about 975 tolerances: nearly magenta.
        let e = (0..3)
            .map(|i| {
                (ours[30 + i] as f64 - reference[30 + i] as f64).abs()
                    / tol(reference[30 + i] as f64)
            })
            .fold(0.0, f64::max);
        assert!((900.0..1000.0).contains(&e), "error {e}");
        assert_eq!(&img[3 * 10..3 * 10 + 3], &error_colour(e), "failing pixel");
        let lum = 0.2126 * 0.3 + 0.7152 * 0.24 + 0.0722 * 0.15;
        let g = (lum * 90.0) as u8;
        assert_eq!(&img[0..3], &[g, g, g], "agreeing pixel: dimmed grey");
        let mut c = c;
        c.class[0] = 1;
        assert_eq!(&diff_image(&c, &ours, &reference)[0..3], &[0, 160, 255]);
        // Every agreeing pixel is its own reference luminance: each pixel and channel a
        // different value, so a grey taken from another pixel or channel shows.
        c.class = vec![0; W * H];
        let n = (W * H) as f32;
        let refr: Vec<f32> = (0..W * H * 3)
            .map(|i| ((i / 3) as f32 + 0.3 * (i % 3) as f32) / n)
            .collect();
        let img = diff_image(&c, &refr, &refr);
        for k in 0..W * H {
            let lum = (0.2126 * refr[3 * k] + 0.7152 * refr[3 * k + 1] + 0.0722 * refr[3 * k + 2])
                .clamp(0.0, 1.0);
            let g = (lum * 90.0) as u8;
            assert_eq!(&img[3 * k..3 * k + 3], &[g, g, g], "agreeing pixel {k}");
        }
    }

    #[test]
    fn the_error_colour_runs_from_yellow_to_magenta_on_a_log_scale() {
        assert_eq!(error_colour(1.0), [255, 255, 0]);
        assert_eq!(error_colour(10f64.powf(1.5)), [255, 90, 0]);
        assert_eq!(error_colour(1000.0), [200, 0, 200]);
        assert_eq!(error_colour(1e9), [200, 0, 200]);
        let g = |e: f64| error_colour(e)[1];
        assert!(
            g(2.0) > g(5.0) && g(5.0) > g(20.0),
            "green falls as the error grows"
        );
    }
}
