//! The camera forms of the file, converted into the one viewing model, with errors
//! located at the field they are about.

use super::error::{SceneError, Source};
use super::format::dv;
use super::format::{self, CameraDesc};
use crate::camera::{Camera, CameraError, ViewingModel, Window};
use toml::Spanned;

pub(super) fn build_camera(
    c: &Spanned<CameraDesc>,
    cols: u32,
    rows: u32,
    src: &Source,
) -> Result<Camera, SceneError> {
    // Every vector of the form must be finite: refused at its own key (the camera's own
    // checks name the quantity they derive, such as the view-plane normal, not the key).
    let (form, vectors): (&str, Vec<(&str, &format::V3)>) = match c.get_ref() {
        CameraDesc::View { vrp, vpn, vup, .. } => {
            ("view", vec![("vrp", vrp), ("vpn", vpn), ("vup", vup)])
        }
        CameraDesc::LookAt { from, at, up, .. } => {
            ("look_at", vec![("from", from), ("at", at), ("up", up)])
        }
        CameraDesc::Povray {
            location,
            direction,
            right,
            up,
        } => (
            "povray",
            vec![
                ("location", location),
                ("direction", direction),
                ("right", right),
                ("up", up),
            ],
        ),
    };
    for (key, v) in vectors {
        if v.iter().any(|x| !x.is_finite()) {
            return Err(src.key_error(
                c.span(),
                key,
                format!("camera.{form}.{key}"),
                "must be finite",
            ));
        }
    }
    let (form, model) = match c.get_ref() {
        CameraDesc::View {
            vrp,
            vpn,
            vup,
            e,
            window,
        } => (
            "view",
            Ok(ViewingModel {
                vrp: dv(*vrp),
                vpn: dv(*vpn),
                vup: dv(*vup),
                e: *e,
                window: Window {
                    left: window.left,
                    right: window.right,
                    bottom: window.bottom,
                    top: window.top,
                },
                cols,
                rows,
            }),
        ),
        CameraDesc::LookAt {
            from,
            at,
            up,
            fov,
            fov_axis,
        } => (
            "look_at",
            ViewingModel::look_at(dv(*from), dv(*at), dv(*up), *fov, *fov_axis, cols, rows),
        ),
        CameraDesc::Povray {
            location,
            direction,
            right,
            up,
        } => (
            "povray",
            ViewingModel::povray(
                dv(*location),
                dv(*direction),
                dv(*right),
                dv(*up),
                cols,
                rows,
            ),
        ),
    };
    model.and_then(Camera::new).map_err(|e| {
        let field = camera_field(form, &e);
        src.key_error(c.span(), field, format!("camera.{form}.{field}"), e)
    })
}

/// The field of a camera form that a camera error is about.
fn camera_field(form: &str, e: &CameraError) -> &'static str {
    use CameraError::*;
    match (form, e) {
        ("view", ZeroVector(s)) if s.contains("vpn") => "vpn",
        ("view", ZeroVector(_)) => "vup",
        ("view", UpParallel) => "vup",
        ("view", EyeDistance(_)) => "e",
        ("view", EmptyWindow) => "window",
        ("view", NonFinite(s)) if s.contains("window") => "window",
        ("view", NonFinite(_)) => "vrp",
        ("look_at", ZeroVector(s)) if s.contains("at") => "at",
        ("look_at", ZeroVector(_) | UpParallel) => "up",
        ("look_at", FieldOfView(_)) => "fov",
        ("look_at", NonFinite(_)) => "from",
        ("povray", ZeroVector("right")) => "right",
        ("povray", ZeroVector("up") | NotOrthogonal(_)) => "up",
        ("povray", ZeroVector(_) | EyeDistance(_)) => "direction",
        ("povray", NonFinite(_)) => "location",
        (_, EmptyPixelArray) => "width",
        _ => "(camera)",
    }
}
