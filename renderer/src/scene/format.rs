//! The scene file format: TOML (1.1, so inline tables may span lines), read with serde.
//! Unknown fields are rejected. Every field is documented in renderer/docs/scene-format.md.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// A 3-vector in the file.
pub type V3 = Exact<f64, 3>;

/// A vector of the file as a glam vector.
pub fn dv(v: V3) -> glam::DVec3 {
    glam::DVec3::from_array(v.0)
}

/// A TOML array of exactly `N` elements. serde's fixed-size arrays read the first `N`
/// elements and ignore the rest; this refuses an array of any other length, so
/// `translate = [1, 0, 0, 99]` is an error, not a translation by (1, 0, 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact<T, const N: usize>(pub [T; N]);

impl<T: Copy + Default, const N: usize> Default for Exact<T, N> {
    fn default() -> Self {
        Exact([T::default(); N])
    }
}

impl<T, const N: usize> std::ops::Deref for Exact<T, N> {
    type Target = [T; N];
    fn deref(&self) -> &[T; N] {
        &self.0
    }
}

impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> serde::de::Visitor<'de>
            for Visit<T, N>
        {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an array of {N} elements")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Self::Value, A::Error> {
                let mut out = [T::default(); N];
                for (k, slot) in out.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(k, &self))?;
                }
                let mut extra = 0;
                while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(serde::de::Error::invalid_length(N + extra, &self));
                }
                Ok(Exact(out))
            }
        }
        d.deserialize_seq(Visit::<T, N>(std::marker::PhantomData))
    }
}

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// The camera, in one of three forms.
    pub camera: Spanned<CameraDesc>,
    /// Render settings.
    pub render: Spanned<RenderDesc>,
    /// Light sources.
    #[serde(default)]
    pub lights: Vec<Spanned<LightDesc>>,
    /// Named materials.
    #[serde(default)]
    pub materials: BTreeMap<String, Spanned<MaterialDesc>>,
    /// Named definitions, placed by `instance` nodes.
    #[serde(default)]
    pub defs: BTreeMap<String, Spanned<NodeDesc>>,
    /// The object tree.
    #[serde(default)]
    pub objects: Vec<Spanned<NodeDesc>>,
}

/// Camera forms. Each converts into the one viewing model.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum CameraDesc {
    /// The viewing model itself.
    View {
        /// View reference point r.
        vrp: V3,
        /// View-plane normal.
        vpn: V3,
        /// Up vector.
        vup: V3,
        /// Eye distance E.
        e: f64,
        /// W_l, W_r, W_b, W_t.
        window: WindowDesc,
    },
    /// Look-at plus a field of view.
    LookAt {
        /// Eye.
        from: V3,
        /// Target.
        at: V3,
        /// Up vector.
        up: V3,
        /// Field of view in degrees.
        fov: f64,
        /// Which extent `fov` spans.
        #[serde(default = "default_fov_axis")]
        fov_axis: crate::camera::FovAxis,
    },
    /// POV-Ray style explicit vectors.
    Povray {
        /// Eye.
        location: V3,
        /// From the eye to the window centre.
        direction: V3,
        /// Full window width along u.
        right: V3,
        /// Full window height along v.
        up: V3,
    },
}

fn default_fov_axis() -> crate::camera::FovAxis {
    crate::camera::FovAxis::Horizontal
}

/// The window on the view plane.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowDesc {
    /// W_l.
    pub left: f64,
    /// W_r.
    pub right: f64,
    /// W_b.
    pub bottom: f64,
    /// W_t.
    pub top: f64,
}

/// Render settings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// Pixel columns.
    pub width: u32,
    /// Pixel rows.
    pub height: u32,
    /// Samples per pixel.
    #[serde(default = "one")]
    pub samples: u32,
    /// Maximum trace depth (POV-Ray's max_trace_level).
    #[serde(default = "five")]
    pub max_depth: u32,
    /// Rays whose weight falls below this are not traced (POV-Ray's adc_bailout).
    #[serde(default = "adc")]
    pub adc_bailout: f64,
    /// Colour of rays that hit nothing.
    #[serde(default)]
    pub background: V3,
    /// Global ambient light (POV-Ray's ambient_light).
    #[serde(default = "white")]
    pub ambient_light: V3,
    /// Light transport: POV-Ray's classic model, or Mitsuba's `direct` or `path`.
    #[serde(default)]
    pub integrator: super::settings::Integrator,
    /// Path integrator: depth from which Russian roulette starts.
    #[serde(default = "five")]
    pub rr_depth: u32,
    /// How samples are placed.
    #[serde(default)]
    pub sampler: crate::sampler::SamplerKind,
    /// Share the samples out by the noise around each pixel.
    #[serde(default)]
    pub adaptive: bool,
    /// Aim some path directions at mirror and glass objects (on unless turned off).
    #[serde(default = "yes")]
    pub guides: bool,
    /// Path integrator: light paths per camera sample for the caustics seen directly
    /// (0, the default, traces none).
    #[serde(default)]
    pub light_paths: f64,
    /// Physical model: every light at each vertex, or one chosen uniformly.
    #[serde(default)]
    pub light_sampling: super::settings::LightSampling,
    /// Intersect in mixed precision the instances the build's precision cannot resolve
    /// (on unless turned off; renderer/docs/precision.md, "Scale against view").
    #[serde(default = "yes")]
    pub mixed_precision: bool,
}

fn yes() -> bool {
    true
}
fn one() -> u32 {
    1
}
fn five() -> u32 {
    5
}
fn adc() -> f64 {
    1.0 / 255.0
}
fn white() -> V3 {
    Exact([1.0; 3])
}

/// A light.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Kind of light.
    #[serde(rename = "type", default)]
    pub kind: crate::light::LightKind,
    /// Point lights: position.
    pub position: Option<V3>,
    /// Directional lights: the direction the light travels.
    pub direction: Option<V3>,
    /// Colour: POV-Ray's light colour (classic); intensity in W/sr (point), irradiance
    /// (directional) or radiance (environment) for the physical integrators.
    #[serde(default = "white")]
    pub color: V3,
    /// Distance at which the fade factor is 1.
    pub fade_distance: Option<f64>,
    /// Fade exponent; fading is on when both fade fields are given and fade_power > 0.
    pub fade_power: Option<f64>,
}

/// A material: POV-Ray's pigment and finish, parameter for parameter (model `classic`),
/// or one of the physical models.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// `classic` (POV-Ray finish), `diffuse`, `conductor` or `dielectric`.
    #[serde(default)]
    pub model: crate::material::MaterialModel,
    /// Emitted radiance (physical integrators): makes a sphere or rectangle an area light.
    pub radiance: Option<V3>,
    /// Pigment colour.
    #[serde(default = "white")]
    pub color: V3,
    /// Pigment filter (filtered transparency).
    #[serde(default)]
    pub filter: f64,
    /// Pigment transmit (unfiltered transparency).
    #[serde(default)]
    pub transmit: f64,
    /// Ambient coefficient.
    #[serde(default = "ambient")]
    pub ambient: f64,
    /// Emission coefficient.
    #[serde(default)]
    pub emission: f64,
    /// Diffuse coefficient.
    #[serde(default = "diffuse")]
    pub diffuse: f64,
    /// Diffuse exponent.
    #[serde(default = "one_f")]
    pub brilliance: f64,
    /// Phong highlight amount.
    #[serde(default)]
    pub phong: f64,
    /// Phong exponent.
    #[serde(default = "phong_size")]
    pub phong_size: f64,
    /// Blinn specular amount.
    #[serde(default)]
    pub specular: f64,
    /// Specular roughness (exponent 1/roughness).
    #[serde(default = "roughness")]
    pub roughness: f64,
    /// Mirror reflection amount.
    #[serde(default)]
    pub reflection: f64,
    /// Index of refraction of the interior.
    #[serde(default = "one_f")]
    pub ior: f64,
}

fn ambient() -> f64 {
    0.1
}
fn diffuse() -> f64 {
    0.6
}
fn one_f() -> f64 {
    1.0
}
fn phong_size() -> f64 {
    40.0
}
fn roughness() -> f64 {
    0.05
}

/// Node kinds of the object tree.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum NodeKind {
    /// Unit sphere.
    Sphere,
    /// Plane y = 0.
    Plane,
    /// Cube [−1, 1]³.
    Box,
    /// Cylinder, y ∈ [−1, 1], radius 1.
    Cylinder,
    /// Cone, apex (0, 1, 0), base radius 1 at y = −1.
    Cone,
    /// Unit disk in y = 0.
    Disk,
    /// [−1, 1]² in y = 0.
    Rectangle,
    /// One triangle.
    Triangle,
    /// A Wavefront OBJ mesh.
    Mesh,
    /// A group of child nodes.
    Group,
    /// A placement of a named definition.
    Instance,
}

/// A node of the object tree.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeDesc {
    /// What the node is.
    #[serde(rename = "type")]
    pub kind: NodeKind,
    /// Optional label, used in error messages.
    pub name: Option<String>,
    /// Material name; inherited from the parent when absent.
    pub material: Option<Spanned<String>>,
    /// Transform operations, applied in order (the first is applied to the object first).
    #[serde(default)]
    pub transform: Vec<Spanned<TransformOp>>,
    /// Cylinder and cone: whether the ends are closed (default true).
    pub capped: Option<bool>,
    /// Triangle: vertices.
    pub vertices: Option<Spanned<Exact<V3, 3>>>,
    /// Triangle: per-vertex shading normals.
    pub normals: Option<Spanned<Exact<V3, 3>>>,
    /// Triangle: per-vertex uv.
    pub uvs: Option<Spanned<Exact<Exact<f64, 2>, 3>>>,
    /// Mesh: OBJ file, relative to the scene file.
    pub file: Option<Spanned<String>>,
    /// Instance: the definition's name.
    pub of: Option<Spanned<String>>,
    /// Group: children.
    pub children: Option<Vec<Spanned<NodeDesc>>>,
}

/// One transform operation.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum TransformOp {
    /// Translation.
    Translate(V3),
    /// Rotation about an axis through the origin, in degrees.
    Rotate {
        /// Axis (any non-zero length).
        axis: V3,
        /// Angle in degrees.
        degrees: f64,
    },
    /// Uniform or per-axis scale.
    Scale(ScaleArg),
    /// Shear: `x += xy·y + xz·z`, `y += yx·x + yz·z`, `z += zx·x + zy·y`.
    Shear(ShearDesc),
    /// Full affine matrix: four rows of three, row-vector convention (POV-Ray's
    /// `matrix`): `p' = p·M + row4`.
    Matrix(Exact<V3, 4>),
}

/// A uniform or per-axis scale.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum ScaleArg {
    /// The same factor on every axis.
    Uniform(f64),
    /// One factor per axis.
    PerAxis(V3),
}

/// Shear factors; missing ones are 0.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ShearDesc {
    /// x += xy·y.
    #[serde(default)]
    pub xy: f64,
    /// x += xz·z.
    #[serde(default)]
    pub xz: f64,
    /// y += yx·x.
    #[serde(default)]
    pub yx: f64,
    /// y += yz·z.
    #[serde(default)]
    pub yz: f64,
    /// z += zx·x.
    #[serde(default)]
    pub zx: f64,
    /// z += zy·y.
    #[serde(default)]
    pub zy: f64,
}

/// Parses scene text; on failure returns the byte span and the field path.
pub fn parse(text: &str) -> Result<SceneDesc, (Option<std::ops::Range<usize>>, String, String)> {
    let table = toml::de::DeTable::parse(text)
        .map_err(|e| (e.span(), String::new(), e.message().to_string()))?;
    parse_table(table, text)
}

/// [`parse`] from a document already parsed into TOML values (with their spans) from
/// `text`, so a caller that inspects the values first parses the text once.
///
/// The values are deserialized without tracking the field path first: the tracking wraps
/// every value of the document and cost about half of loading a scene of 10,000 objects
/// (renderer/docs/performance.md). Only when that fails is `text` parsed again and
/// deserialized with the tracking, to name the field; the two differ in nothing else, so
/// they fail alike.
pub fn parse_table(
    table: toml::Spanned<toml::de::DeTable<'_>>,
    text: &str,
) -> Result<SceneDesc, (Option<std::ops::Range<usize>>, String, String)> {
    if let Ok(desc) =
        <SceneDesc as serde::Deserialize>::deserialize(toml::Deserializer::from(table))
    {
        return Ok(desc);
    }
    let table = toml::de::DeTable::parse(text)
        .map_err(|e| (e.span(), String::new(), e.message().to_string()))?;
    let de = toml::Deserializer::from(table);
    serde_path_to_error::deserialize(de).map_err(|e| {
        // `Spanned<T>` appears in the path as a private wrapper field; drop it.
        let path = e
            .path()
            .to_string()
            .replace(".$__serde_spanned_private_value", "");
        let inner = e.into_inner();
        let span = inner.span();
        // An enum's name written as a value is quoted; as a key (`[camera.lookat]`) it is not.
        let quoted = span
            .clone()
            .and_then(|r| text.get(r))
            .is_some_and(|t| t.trim_start().starts_with(['"', '\'']));
        let message = super::error::reword(inner.message(), !quoted);
        (span, path, message)
    })
}
