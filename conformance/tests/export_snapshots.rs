//! Snapshots of the exported POV-Ray SDL for a few scenes: camera vectors, matrices,
//! textures and interiors, declared definitions and meshes. A change to the exporter shows
//! up here as a reviewable diff (and makes every reference stale through its export hash).

use conformance::catalog::load;
use conformance::catalog::scenes;

fn sdl(name: &str) -> String {
    let e = scenes("povray", name)
        .unwrap()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap();
    let (scene, _) = load(&e).unwrap();
    conformance::povray::export(&scene, name)
}

#[test]
fn test01_sphere_identity() {
    insta::assert_snapshot!(sdl("prim_sphere_identity"));
}

#[test]
fn test02_asymmetric_window_camera() {
    insta::assert_snapshot!(sdl("cam_asymmetric"));
}

#[test]
fn test03_sheared_cone_matrix() {
    insta::assert_snapshot!(sdl("prim_cone_shear"));
}

#[test]
fn test04_glass_interior() {
    insta::assert_snapshot!(sdl("shade_refract_sphere"));
}

#[test]
fn test05_three_level_hierarchy() {
    insta::assert_snapshot!(sdl("hier_three_levels"));
}

#[test]
fn test06_mesh2() {
    let s = sdl("prim_mesh_identity");
    // The icosphere has 162 vertices and 320 faces, declared once.
    assert_eq!(s.matches("#declare Mesh0 = mesh2").count(), 1);
    assert!(
        s.contains("vertex_vectors { 162,")
            && s.contains("normal_vectors { 162,")
            && s.contains("face_indices { 320,")
    );
    insta::assert_snapshot!(s);
}

fn xml(name: &str) -> String {
    let e = scenes("mitsuba", name)
        .unwrap()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap();
    let (scene, _) = load(&e).unwrap();
    let export = conformance::mitsuba::export(&scene, 64, true).unwrap();
    let mut s = export.xml;
    for (file, obj) in export.meshes {
        s.push_str(&format!("\n=== {file} (first 6 lines) ===\n"));
        for line in obj.lines().take(6) {
            s.push_str(line);
            s.push('\n');
        }
    }
    s
}

#[test]
fn test07_mitsuba_point_light_and_spheres() {
    insta::assert_snapshot!(xml("mi_diffuse_point"));
}

#[test]
fn test08_mitsuba_shapegroup_for_an_ellipsoid() {
    let s = xml("mi_ellipsoid");
    assert!(s.contains("type=\"shapegroup\"") && s.contains("type=\"instance\""));
    insta::assert_snapshot!(s);
}

#[test]
fn test09_mitsuba_mirrored_and_meshes() {
    insta::assert_snapshot!(xml("mi_mirrored"));
    insta::assert_snapshot!(xml("mi_mesh"));
}

#[test]
fn test10_mitsuba_area_lights_and_path() {
    let s = xml("mi_cornell");
    assert!(s.contains("<emitter type=\"area\">") && s.contains("<integrator type=\"path\">"));
    insta::assert_snapshot!(s);
}

#[test]
fn test11_mitsuba_refuses_what_it_cannot_express() {
    // Non-square pixels, cones and classic materials have no Mitsuba equivalent.
    let e = scenes("povray", "cam_nonsquare").unwrap().remove(0);
    let (scene, _) = load(&e).unwrap();
    let err = conformance::mitsuba::export(&scene, 1, false)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("not square"), "{err}");
}
