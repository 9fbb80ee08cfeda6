//! The viewing model: the formulas of DEVELOPERS.md on an asymmetric window and a
//! non-square pixel array, the conversions between camera forms, and the degenerate cases.

use glam::DVec3;
use renderer::camera::{view_basis, Camera, CameraError, FovAxis, ViewingModel, Window};
use renderer::real::dvec3;

/// Relative tolerance for comparing a renderer-precision ray with an f64 reference.
const TOL: f64 = if cfg!(feature = "f64") { 1e-12 } else { 2e-6 };

fn oblique() -> ViewingModel {
    ViewingModel {
        vrp: DVec3::new(3.0, -2.0, 5.5),
        vpn: DVec3::new(-0.4, 0.3, 1.0),
        vup: DVec3::new(0.35, 1.0, -0.1), // rolled
        e: 2.5,
        window: Window {
            left: -1.5,
            right: 0.5,
            bottom: -0.2,
            top: 0.8,
        },
        cols: 7,
        rows: 3,
    }
}

fn close(a: DVec3, b: DVec3, scale: f64) -> bool {
    (a - b).length() <= TOL * scale.max(1.0)
}

fn ray64(c: &Camera, i: u32, j: u32) -> (DVec3, DVec3) {
    let r = c.pixel_ray(i, j);
    (dvec3(r.o), dvec3(r.d))
}

#[test]
fn test01_pixel_rays_follow_the_viewing_model_formulas() {
    let m = oblique();
    let cam = Camera::new(m).unwrap();
    // The reference, computed here from the definitions alone.
    let n = m.vpn.normalize();
    let v = (m.vup - n * m.vup.dot(n)).normalize();
    let u = v.cross(n);
    let to_world = |p: DVec3| u * p.x + v * p.y + n * p.z; // p M, M = rows u, v, n
    let eye = to_world(DVec3::new(0.0, 0.0, -m.e)) + m.vrp;
    let du = (m.window.right - m.window.left) / m.cols as f64;
    let dv = (m.window.top - m.window.bottom) / m.rows as f64;
    for j in 0..m.rows {
        for i in 0..m.cols {
            let ui = m.window.left + (i as f64 + 0.5) * du;
            let vj = m.window.top - (j as f64 + 0.5) * dv;
            let dir = to_world(DVec3::new(ui, vj, m.e));
            let (o, d) = ray64(&cam, i, j);
            assert!(
                close(o, eye, eye.length()),
                "eye at pixel ({i},{j}): {o} vs {eye}"
            );
            assert!(
                close(d, dir, dir.length()),
                "dir at pixel ({i},{j}): {d} vs {dir}"
            );
            // The ray passes through its window point (u_i, v_j, 0) in view coordinates.
            let window_point = to_world(DVec3::new(ui, vj, 0.0)) + m.vrp;
            assert!(close(o + d, window_point, window_point.length()));
        }
    }
    // World to view maps the eye to (0, 0, -E): [a b c] = (x - r) Mᵀ.
    let view = |x: DVec3| {
        let q = x - m.vrp;
        DVec3::new(q.dot(u), q.dot(v), q.dot(n))
    };
    assert!((view(dvec3(cam.eye())) - DVec3::new(0.0, 0.0, -m.e)).length() < TOL * 10.0);
    // Corners: pixel (0, 0) is top-left, (cols-1, rows-1) bottom-right.
    let (_, d00) = ray64(&cam, 0, 0);
    let (_, d62) = ray64(&cam, 6, 2);
    assert!(d00.dot(u) < d62.dot(u) && d00.dot(v) > d62.dot(v));
}

#[test]
fn test02_basis_is_orthonormal_and_left_handed() {
    let [u, v, n] = view_basis(DVec3::Z, DVec3::Y).unwrap();
    assert_eq!(
        (u, v, n),
        (DVec3::X, DVec3::Y, DVec3::Z),
        "identity view: u = x (image right)"
    );
    let m = oblique();
    let [u, v, n] = view_basis(m.vpn, m.vup).unwrap();
    for (a, b) in [(u, v), (v, n), (n, u)] {
        assert!(a.dot(b).abs() < 1e-15);
    }
    for a in [u, v, n] {
        assert!((a.length() - 1.0).abs() < 1e-15);
    }
    // u = v × n: with x right and y up, n points into the screen (left-handed).
    assert!((u - v.cross(n)).length() < 1e-15);
    // v lies in the plane of vup and n, on vup's side.
    assert!(v.dot(m.vup) > 0.0 && v.cross(n).dot(m.vup.cross(n)) > 0.0);
}

#[test]
fn test03_povray_form_gives_identical_rays() {
    let m = oblique();
    let cam = Camera::new(m).unwrap();
    let [loc, dir, right, up] = m.to_povray().unwrap();
    let back =
        Camera::new(ViewingModel::povray(loc, dir, right, up, m.cols, m.rows).unwrap()).unwrap();
    // POV-Ray's own formula (tracepixel.cpp): direction + x·right + y·up from location.
    for j in 0..m.rows {
        for i in 0..m.cols {
            let x = (i as f64 + 0.5) / m.cols as f64 - 0.5;
            let y = 0.5 - (j as f64 + 0.5) / m.rows as f64;
            let pov = dir + right * x + up * y;
            let (o1, d1) = ray64(&cam, i, j);
            let (o2, d2) = ray64(&back, i, j);
            assert!(
                close(d1, pov, pov.length()),
                "viewing model vs POV-Ray formula at ({i},{j})"
            );
            assert!(
                close(d2, pov, pov.length()),
                "converted camera vs POV-Ray formula at ({i},{j})"
            );
            assert!(close(o1, loc, loc.length()) && close(o2, loc, loc.length()));
        }
    }
}

#[test]
fn test04_look_at_form_gives_identical_rays() {
    let (from, at, up) = (
        DVec3::new(1.0, 2.0, -4.0),
        DVec3::new(0.5, 0.0, 1.0),
        DVec3::new(0.1, 1.0, 0.0),
    );
    let (cols, rows) = (320, 120);
    for (axis, fov) in [(FovAxis::Horizontal, 70.0f64), (FovAxis::Vertical, 25.0)] {
        let look = Camera::new(ViewingModel::look_at(from, at, up, fov, axis, cols, rows).unwrap())
            .unwrap();
        // The same camera written directly in the viewing model, with E = 3 this time.
        let e = 3.0;
        let half = (fov.to_radians() * 0.5).tan();
        let aspect = cols as f64 / rows as f64;
        let (hw, hh) = match axis {
            FovAxis::Horizontal => (half * e, half * e / aspect),
            FovAxis::Vertical => (half * e * aspect, half * e),
        };
        let n = (at - from).normalize();
        let direct = Camera::new(ViewingModel {
            vrp: from + n * e,
            vpn: at - from,
            vup: up,
            e,
            window: Window {
                left: -hw,
                right: hw,
                bottom: -hh,
                top: hh,
            },
            cols,
            rows,
        })
        .unwrap();
        for (i, j) in [(0, 0), (319, 0), (0, 119), (160, 60), (17, 101)] {
            let (o1, d1) = ray64(&look, i, j);
            let (o2, d2) = ray64(&direct, i, j);
            assert!(close(o1, o2, o1.length()));
            // Same direction up to length (E differs): compare unit vectors.
            assert!(
                close(d1.normalize(), d2.normalize(), 1.0),
                "{axis:?} pixel ({i},{j})"
            );
        }
        // The field of view spans the window edge to edge.
        let dir = |x: f64, y: f64| dvec3(look.ray_at(x, y).d);
        let (w, h) = (cols as f64, rows as f64);
        let measured = match axis {
            FovAxis::Horizontal => dir(0.0, h / 2.0).angle_between(dir(w, h / 2.0)),
            FovAxis::Vertical => dir(w / 2.0, 0.0).angle_between(dir(w / 2.0, h)),
        }
        .to_degrees();
        assert!(
            (measured - fov).abs() < 1e-3,
            "{axis:?}: {measured}° vs {fov}°"
        );
    }
}

#[test]
fn test05_degenerate_cameras_are_errors() {
    let ok = oblique();
    let with = |f: &dyn Fn(&mut ViewingModel)| {
        let mut m = ok;
        f(&mut m);
        Camera::new(m).unwrap_err()
    };
    assert_eq!(with(&|m| m.vup = m.vpn * 3.0), CameraError::UpParallel);
    assert_eq!(with(&|m| m.vup = -m.vpn), CameraError::UpParallel);
    assert!(matches!(
        with(&|m| m.vpn = DVec3::ZERO),
        CameraError::ZeroVector(_)
    ));
    assert!(matches!(
        with(&|m| m.vup = DVec3::ZERO),
        CameraError::ZeroVector(_)
    ));
    assert!(matches!(with(&|m| m.e = 0.0), CameraError::EyeDistance(_)));
    assert!(matches!(with(&|m| m.e = -1.0), CameraError::EyeDistance(_)));
    assert_eq!(
        with(&|m| m.window.right = m.window.left),
        CameraError::EmptyWindow
    );
    assert_eq!(
        with(&|m| m.window.top = m.window.bottom - 1.0),
        CameraError::EmptyWindow
    );
    assert_eq!(with(&|m| m.cols = 0), CameraError::EmptyPixelArray);
    assert!(matches!(
        with(&|m| m.vrp.x = f64::NAN),
        CameraError::NonFinite(_)
    ));
    let z = DVec3::ZERO;
    assert!(ViewingModel::look_at(z, z, DVec3::Y, 60.0, FovAxis::Horizontal, 4, 4).is_err());
    assert!(ViewingModel::look_at(z, DVec3::Y, DVec3::Y, 60.0, FovAxis::Horizontal, 4, 4).is_err());
    assert!(
        ViewingModel::look_at(z, DVec3::Z, DVec3::Y, 180.0, FovAxis::Horizontal, 4, 4).is_err()
    );
    // Skewed POV-Ray vectors cannot be expressed in the viewing model.
    assert!(ViewingModel::povray(z, DVec3::Z, DVec3::X, DVec3::new(0.5, 1.0, 0.0), 4, 4).is_err());
    // Direction behind the image plane.
    assert!(ViewingModel::povray(z, -DVec3::Z, DVec3::X, DVec3::Y, 4, 4).is_err());
}
