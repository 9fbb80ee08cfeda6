//! The materials of the file, validated where they are written. Index 0 is the default
//! material; the map gives each name's index.

use super::error::{SceneError, Source};
use super::format::MaterialDesc;
use super::{Color, Material, MaterialModel};
use std::collections::{BTreeMap, HashMap};
use toml::Spanned;

/// A colour of the file, in the renderer's colour precision.
pub(super) fn color(v: super::format::V3) -> Color {
    Color::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// The materials (the default first) and the index of each name.
pub(super) fn build_materials(
    descs: &BTreeMap<String, Spanned<MaterialDesc>>,
    classic: bool,
    src: &Source,
) -> Result<(Vec<Material>, HashMap<String, u32>), SceneError> {
    let mut materials = vec![Material::default()];
    let mut material_index = HashMap::new();
    for (name, m) in descs {
        let d = m.get_ref();
        let field = format!("materials.{name}");
        let scalars = [
            ("filter", d.filter),
            ("transmit", d.transmit),
            ("ambient", d.ambient),
            ("emission", d.emission),
            ("diffuse", d.diffuse),
            ("brilliance", d.brilliance),
            ("phong", d.phong),
            ("phong_size", d.phong_size),
            ("specular", d.specular),
            ("roughness", d.roughness),
            ("reflection", d.reflection),
            ("ior", d.ior),
        ];
        let err =
            |key: &str, msg: &str| src.key_error(m.span(), key, format!("{field}.{key}"), msg);
        for (key, x) in scalars {
            if !x.is_finite() || x < 0.0 {
                return Err(err(key, "must be finite and ≥ 0"));
            }
        }
        if d.filter + d.transmit > 1.0 {
            return Err(err(
                "transmit",
                &format!(
                    "filter + transmit = {} is more than 1: more light would pass through \
    than arrives, and the surface's own colour would count negatively",
                    d.filter + d.transmit
                ),
            ));
        }
        if d.color.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("color", "components must be finite and ≥ 0"));
        }
        if d.roughness == 0.0 && d.specular > 0.0 {
            return Err(err("roughness", "must be > 0 when specular is used"));
        }
        if d.ior == 0.0 {
            return Err(err("ior", "must be > 0"));
        }
        if classic != (d.model == MaterialModel::Classic) {
            return Err(err(
                "model",
                if classic {
                    "a physical material needs render.integrator = \"direct\" or \"path\""
                } else {
                    "the direct and path integrators need model = \"diffuse\", \"conductor\" or \"dielectric\""
                },
            ));
        }
        let radiance = d.radiance.unwrap_or_default();
        if radiance.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("radiance", "components must be finite and ≥ 0"));
        }
        if classic && d.radiance.is_some() {
            return Err(err(
                "radiance",
                "area lights need the direct or path integrator",
            ));
        }
        material_index.insert(name.clone(), materials.len() as u32);
        materials.push(Material {
            name: name.clone(),
            model: d.model,
            radiance: color(radiance),
            color: color(d.color),
            filter: d.filter as f32,
            transmit: d.transmit as f32,
            ambient: d.ambient as f32,
            emission: d.emission as f32,
            diffuse: d.diffuse as f32,
            brilliance: d.brilliance as f32,
            phong: d.phong as f32,
            phong_size: d.phong_size as f32,
            specular: d.specular as f32,
            roughness: d.roughness as f32,
            reflection: d.reflection as f32,
            ior: d.ior as f32,
        });
    }
    Ok((materials, material_index))
}
