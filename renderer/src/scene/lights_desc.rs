//! The lights of the file, validated where they are written. Positions stay in world
//! coordinates here; the builder moves them into render space once its origin is known.

use super::error::{SceneError, Source};
use super::format::{dv, LightDesc};
use super::materials_desc::color;
use super::{Light, LightKind};
use crate::real::{vec3, Real};
use glam::DVec3;
use toml::Spanned;

/// The lights, and each one's position in world coordinates (0 for lights without one).
pub(super) fn build_lights(
    descs: &[Spanned<LightDesc>],
    classic: bool,
    src: &Source,
) -> Result<(Vec<Light>, Vec<DVec3>), SceneError> {
    let mut lights = Vec::new();
    let mut light_positions = Vec::new();
    for (k, l) in descs.iter().enumerate() {
        let d = l.get_ref();
        let field = format!("lights[{k}]");
        let err = |f: &str, m: &str| src.key_error(l.span(), f, format!("{field}.{f}"), m);
        let (mut position, mut direction) = (DVec3::ZERO, DVec3::ZERO);
        match d.kind {
            LightKind::Point => {
                let p = d
                    .position
                    .ok_or_else(|| err("position", "a point light needs a position"))?;
                if p.iter().any(|x| !x.is_finite()) {
                    return Err(err("position", "must be finite"));
                }
                position = dv(p);
            }
            LightKind::Directional => {
                let v = dv(d
                    .direction
                    .ok_or_else(|| err("direction", "a directional light needs a direction"))?);
                if !(v.length() > 0.0 && v.is_finite()) {
                    return Err(err("direction", "must be a finite, non-zero vector"));
                }
                direction = v.normalize();
            }
            LightKind::Environment => {}
        }
        light_positions.push(position);
        if d.kind != LightKind::Point && classic {
            return Err(err(
                "type",
                "directional and environment lights need the direct or path integrator",
            ));
        }
        if d.kind != LightKind::Point && d.position.is_some() {
            return Err(err("position", "only point lights have a position"));
        }
        if d.kind != LightKind::Directional && d.direction.is_some() {
            return Err(err("direction", "only directional lights have a direction"));
        }
        if d.color.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("color", "components must be finite and ≥ 0"));
        }
        let fade = match (d.fade_distance, d.fade_power) {
            (Some(dist), Some(pow)) if pow > 0.0 => {
                if !(dist > 0.0 && dist.is_finite() && pow.is_finite()) {
                    return Err(err(
                        "fade_distance",
                        "fade_distance must be > 0 and both finite",
                    ));
                }
                Some((dist as Real, pow as Real))
            }
            _ => None,
        };
        lights.push(Light {
            kind: d.kind,
            // World coordinates for now; moved into render space once the origin is known.
            position: vec3(position),
            direction: vec3(direction),
            color: color(d.color),
            fade,
        });
    }
    Ok((lights, light_positions))
}
