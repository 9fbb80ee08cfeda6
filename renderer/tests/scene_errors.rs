//! Bad input gets a clear error naming the file, the line and column, and the field; it
//! never panics and never leaves an output file behind.

use renderer::scene::{Scene, SceneError};
use std::path::Path;

const CAMERA: &str = r#"
[camera.view]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
e = 1
window = { left = -1, right = 1, bottom = -1, top = 1 }

[render]
width = 8
height = 8
"#;

fn load(text: &str) -> Result<Scene, SceneError> {
    Scene::from_str(text, Path::new("bad.toml"), Path::new("."))
}

/// Asserts that `text` fails at `line` with a field path containing `field` and a message
/// containing `msg`.
fn check(text: &str, line: usize, field: &str, msg: &str) {
    let e = load(text).expect_err("the scene must be rejected");
    assert_eq!(e.file, "bad.toml");
    assert_eq!(e.line, line, "line of: {e}");
    assert!(e.column >= 1, "column of: {e}");
    assert!(
        e.field.contains(field),
        "field '{}' should contain '{field}': {e}",
        e.field
    );
    assert!(
        e.message.contains(msg),
        "message should contain '{msg}': {e}"
    );
    // The rendered message starts with file:line:column.
    assert!(e
        .to_string()
        .starts_with(&format!("bad.toml:{line}:{}", e.column)));
}

#[test]
fn test01_syntax_error_has_a_position() {
    check("[camera.view\nvrp = [0,0,0]\n", 1, "(syntax)", "");
}

#[test]
fn test02_unknown_field_is_rejected() {
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\nradius = 2\n");
    check(&text, 15, "objects[0].radius", "unknown key `radius`");
}

#[test]
fn test03_wrong_type_names_the_field() {
    let text = CAMERA.replace("width = 8", "width = \"eight\"");
    check(&text, 10, "render.width", "invalid type");
}

#[test]
fn test04_unknown_shape_type() {
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"torus\"\n");
    check(&text, 14, "objects[0].type", "unknown value `torus`");
}

#[test]
fn test05_up_parallel_to_vpn() {
    check(
        &CAMERA.replace("vup = [0, 1, 0]", "vup = [0, 0, 2]"),
        5,
        "camera.view.vup",
        "parallel",
    );
}

#[test]
fn test06_zero_vectors_and_eye_distance() {
    check(
        &CAMERA.replace("vpn = [0, 0, 1]", "vpn = [0, 0, 0]"),
        4,
        "camera.view.vpn",
        "zero-length",
    );
    check(
        &CAMERA.replace("e = 1", "e = 0"),
        6,
        "camera.view.e",
        "E must be > 0",
    );
    check(
        &CAMERA.replace("e = 1", "e = -2"),
        6,
        "camera.view.e",
        "E must be > 0",
    );
    check(
        &CAMERA.replace("right = 1", "right = -1"),
        7,
        "camera.view.window",
        "empty",
    );
}

#[test]
fn test07_singular_transform_names_the_operation() {
    let text = format!(
        "{CAMERA}\n[[objects]]\ntype = \"group\"\nchildren = [\n  {{ type = \"sphere\" }},\n  {{ type = \"box\", transform = [{{ translate = [1, 0, 0] }},\n    {{ scale = [1, 0, 1] }}] }},\n]\n"
    );
    check(&text, 18, "objects[0].children[1].transform[1]", "singular");
}

#[test]
fn test08_non_finite_and_composed_singular_transforms() {
    // A huge scale is fine alone, but nan is not representable in TOML except as `nan`.
    let text = format!(
        "{CAMERA}\n[[objects]]\ntype = \"sphere\"\ntransform = [{{ translate = [nan, 0, 0] }}]\n"
    );
    check(&text, 15, "objects[0].transform[0]", "non-finite");
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\ntransform = [{{ rotate = {{ axis = [0, 0, 0], degrees = 10 }} }}]\n");
    check(&text, 15, "objects[0].transform[0]", "zero-length");
}

#[test]
fn test09_references_must_resolve() {
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\nmaterial = \"gold\"\n");
    check(&text, 15, "objects[0].material", "no material named 'gold'");
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"instance\"\nof = \"tree\"\n");
    check(&text, 15, "of", "no definition named 'tree'");
    let text = format!("{CAMERA}\n[defs.a]\ntype = \"instance\"\nof = \"a\"\n\n[[objects]]\ntype = \"instance\"\nof = \"a\"\n");
    check(&text, 15, "of", "contains itself");
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"mesh\"\nfile = \"no/such.obj\"\n");
    check(&text, 15, "objects[0].file", "no/such.obj");
}

#[test]
fn test10_fields_must_match_the_kind() {
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\ncapped = true\n");
    check(&text, 15, "objects[0].capped", "not a field of a sphere");
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]\n");
    check(&text, 15, "objects[0].vertices", "degenerate");
}

#[test]
fn test11_render_settings_are_validated() {
    check(
        &CAMERA.replace("width = 8", "width = 0"),
        10,
        "render.width",
        "at least 1",
    );
    // Each side is named on its own line.
    check(
        &CAMERA.replace("height = 8", "height = 0"),
        11,
        "render.height",
        "at least 1",
    );
    // An image too large to allocate is refused before any allocation, with the amount.
    check(
        &CAMERA
            .replace("width = 8", "width = 1000000")
            .replace("height = 8", "height = 1000000"),
        10,
        "render.width",
        "more than the limit of 134217728 (2^27): a render could need 168000.0 GB",
    );
    let text = format!("{CAMERA}samples = 0\n");
    check(&text, 12, "render.samples", "at least 1");
    let text = format!("{CAMERA}\n[materials.m]\nior = -1.5\n");
    check(&text, 14, "materials.m.ior", "≥ 0");
}

#[test]
fn test11b_models_must_match_the_integrator() {
    let text = format!("{CAMERA}\n[materials.m]\nmodel = \"diffuse\"\n");
    check(&text, 14, "materials.m.model", "needs render.integrator");
    let text = format!(
        "{}\n[materials.m]\ncolor = [1, 1, 1]\n",
        CAMERA.replace("height = 8", "height = 8\nintegrator = \"path\"")
    );
    // `model` is not written: the error points at the material's table.
    check(&text, 14, "materials.m.model", "need model");
    let text = format!("{CAMERA}\n[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n");
    check(
        &text,
        14,
        "lights[0].type",
        "need the direct or path integrator",
    );
    let path = CAMERA.replace("height = 8", "height = 8\nintegrator = \"path\"");
    let text = format!("{path}\n[[lights]]\ntype = \"directional\"\n");
    check(&text, 14, "lights[0].direction", "needs a direction");
    let text = format!("{path}\n[materials.glow]\nmodel = \"diffuse\"\nradiance = [1, 1, 1]\n\n[[objects]]\ntype = \"box\"\nmaterial = \"glow\"\n");
    check(
        &text,
        20,
        "objects[0].material",
        "only be on a sphere or a rectangle",
    );
}

#[test]
fn test12_missing_file_is_an_error_not_a_panic() {
    let e = Scene::load(Path::new("/no/such/scene.toml")).unwrap_err();
    // The file and the system's reason, and no line, column or field: there is none.
    assert_eq!(
        e.to_string(),
        "/no/such/scene.toml: cannot read the scene file: No such file or directory (os error 2)",
        "the message of a scene file that is not there"
    );
    assert_eq!((e.line, e.column), (0, 0), "{e}");
}

/// The command line: a bad scene exits with status 2, prints the located error, and writes
/// no output file (not even a partial one).
#[test]
fn test13_cli_reports_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("renderer-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, CAMERA.replace("vup = [0, 1, 0]", "vup = [0, 0, 1]")).unwrap();
    let out = dir.join("out.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_renderer"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("bad.toml:5:1: camera.view.vup"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        std::fs::read_dir(&dir).unwrap().count() == 1,
        "nothing but the scene may be in {dir:?}"
    );

    // A good scene to an unwritable place fails cleanly too, leaving no temporary file.
    std::fs::write(&scene, CAMERA).unwrap();
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_renderer"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.join("missing-dir/out.exr").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(std::fs::read_dir(&dir).unwrap().count() == 1);
    // And an unknown extension is refused before rendering.
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_renderer"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.join("out.jpg").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("unknown output format"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test20_arrays_of_the_wrong_length_are_refused_not_truncated() {
    let obj = |extra: &str| format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\n{extra}\n");
    check(
        &obj("transform = [{ translate = [1, 0, 0, 99] }]"),
        15,
        "objects[0].transform[0].translate",
        "invalid length 4, expected an array of 3 elements",
    );
    check(
        &obj("transform = [{ matrix = [[1,0,0],[0,1,0],[0,0,1],[0,0,0],[9,9,9]] }]"),
        15,
        "objects[0].transform[0].matrix",
        "invalid length 5, expected an array of 4 elements",
    );
    check(
        &format!("{CAMERA}[[lights]]\nposition = [0, 1, 0]\ncolor = [1, 1, 1, \"x\"]\n"),
        14,
        "lights[0].color",
        "invalid length 4",
    );
    check(
        &format!("{CAMERA}\n[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\n"),
        15,
        "objects[0].vertices",
        "invalid length 4",
    );
    check(
        &CAMERA.replace("vrp = [0, 0, 0]", "vrp = [0, 0]"),
        3,
        "camera.view.vrp",
        "invalid length 2",
    );
}

#[test]
fn test21_numbers_beyond_the_render_precision_are_refused_where_they_are_written() {
    if cfg!(feature = "f64") {
        // 1e39 is an ordinary number in f64: the scene loads.
        load(&CAMERA.replace("vrp = [0, 0, 0]", "vrp = [1e39, 0, 0]")).unwrap();
        return;
    }
    for (text, line, field) in [
        (CAMERA.replace("vrp = [0, 0, 0]", "vrp = [1e39, 0, 0]"), 3, "camera.view.vrp[0]"),
        (CAMERA.replace("left = -1", "left = -1e39"), 7, "camera.view.window.left"),
        (format!("{CAMERA}background = [0, 1e39, 0]\n"), 12, "render.background[1]"),
        (format!("{CAMERA}[[lights]]\nposition = [0, 1, 0]\ncolor = [1, 1, 4e38]\n"), 14, "lights[0].color[2]"),
        (format!("{CAMERA}[materials.m]\nphong_size = 1e40\n"), 13, "materials.m.phong_size"),
        (format!("{CAMERA}\n[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1e39, 0, 0], [0, 1, 0]]\n"), 15, "objects[0].vertices[1][0]"),
    ] {
        check(&text, line, field, "beyond the largest number of the renderer's precision");
    }
    // Finite vertices whose normal (a cross product) overflows.
    check(
        &format!("{CAMERA}\n[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1e20, 0, 0], [0, 1e20, 0]]\n"),
        15,
        "objects[0].vertices",
        "the triangle's normal overflows",
    );
}

#[test]
fn test22_filter_and_transmit_together_may_not_exceed_one() {
    check(
        &format!("{CAMERA}[materials.m]\nfilter = 0.7\ntransmit = 0.5\n"),
        14,
        "materials.m.transmit",
        "filter + transmit = 1.2 is more than 1",
    );
    load(&format!(
        "{CAMERA}[materials.m]\nfilter = 0.5\ntransmit = 0.5\n"
    ))
    .unwrap();
}

#[test]
fn test23_a_transform_too_large_is_reported_as_an_overflow() {
    let obj = |t: &str| format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\ntransform = [{t}]\n");
    // In f32 both overflow; in f64 only the second (1e60 is an ordinary f64 scale).
    let cases: &[&str] = if cfg!(feature = "f64") {
        &["{ scale = 1e200 }, { scale = 1e200 }"]
    } else {
        &[
            "{ scale = 1e30 }, { scale = 1e30 }",
            "{ scale = 1e200 }, { scale = 1e200 }",
        ]
    };
    for t in cases {
        let e = load(&obj(t)).expect_err(t);
        assert!(
            e.message.contains("overflow") || e.message.contains("beyond the largest number"),
            "{t}: {e}"
        );
        assert!(
            !e.message.contains("singular"),
            "{t}: an overflow reported as singular: {e}"
        );
    }
}

#[test]
fn test24_a_mesh_that_is_not_a_regular_file_is_refused() {
    let e = load(&format!(
        "{CAMERA}\n[[objects]]\ntype = \"mesh\"\nfile = \"/dev/zero\"\n"
    ))
    .expect_err("/dev/zero is not a mesh");
    assert!(e.message.contains("not a regular file"), "{e}");
    assert_eq!(e.field, "objects[0].file");
}

/// A scene file in a scratch folder, for errors that need a real file (meshes).
fn scratch_scene(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("renderer-errors-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn test25_a_missing_mesh_names_where_it_was_looked_for() {
    // Mesh paths are relative to the scene file, not to the working directory: the error
    // gives the path as written and the path it resolved to.
    let path = scratch_scene(
        "mesh",
        &format!("{CAMERA}\n[[objects]]\ntype = \"mesh\"\nfile = \"meshes/gone.obj\"\n"),
    );
    let e = Scene::load(&path).expect_err("the mesh is not there");
    let resolved = path.parent().unwrap().join("meshes/gone.obj");
    assert_eq!((e.line, e.field.as_str()), (15, "objects[0].file"), "{e}");
    assert!(
        e.message.contains("'meshes/gone.obj'")
            && e.message
                .contains(&format!("looked for at {}", resolved.display())),
        "the message should give the path as written and as resolved ({}): {e}",
        resolved.display()
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn test26_misspelt_names_get_a_suggestion() {
    // Materials, definitions, keys (camera tables and transform operations included) and
    // enum values: one wording, and the closest names from the same edit-distance code.
    let shiny = "[materials.shiny]\nphong = 0.5\n";
    let text =
        format!("{CAMERA}\n{shiny}\n[[objects]]\ntype = \"sphere\"\nmaterial = \"shinny\"\n");
    check(
        &text,
        18,
        "objects[0].material",
        "no material named 'shinny' (did you mean 'shiny'?)",
    );
    let text = format!("{CAMERA}\n[defs.tree]\ntype = \"sphere\"\n\n[[objects]]\ntype = \"instance\"\nof = \"tre\"\n");
    check(
        &text,
        18,
        "of",
        "no definition named 'tre' (did you mean 'tree'?)",
    );
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphree\"\n");
    check(
        &text,
        14,
        "objects[0].type",
        "unknown value `sphree` (did you mean 'sphere'?); the values allowed here: sphere, plane",
    );
    let text = format!("{CAMERA}\n[[objects]]\ntype = \"sphere\"\nmaterail = \"x\"\n");
    check(
        &text,
        15,
        "objects[0].materail",
        "unknown key `materail` (did you mean 'material'?)",
    );
    let text = CAMERA.replace("[camera.view]", "[camera.veiw]");
    let e = load(&text).expect_err("an unknown camera form");
    assert!(
        e.message.starts_with("unknown key `veiw` (did you mean 'view'?); the keys allowed here: view, look_at, povray"),
        "a camera table is a key like any other: {e}"
    );
    let text = CAMERA.replace("e = 1", "ee = 1");
    check(
        &text,
        6,
        "camera.view",
        "unknown key `ee` (did you mean 'e'?)",
    );
    let text = format!(
        "{CAMERA}\n[[objects]]\ntype = \"sphere\"\ntransform = [{{ translat = [1, 0, 0] }}]\n"
    );
    let e = load(&text).expect_err("an unknown transform operation");
    assert!(
        e.message
            .starts_with("unknown key `translat` (did you mean 'translate'?)"),
        "a transform operation is a key: {e}"
    );
}

#[test]
fn test27_a_bad_number_says_number() {
    let text = CAMERA.replace("e = 1", "e = \"one\"");
    check(&text, 6, "camera.view.e", "expected a number");
    let e = load(&text).unwrap_err();
    assert!(
        !e.message.contains("f64"),
        "a Rust type name in the message: {e}"
    );
    let text = CAMERA.replace("width = 8", "width = -8");
    let e = load(&text).unwrap_err();
    assert!(
        e.message.contains("a whole number") && !e.message.contains("u32"),
        "a Rust type name in the message: {e}"
    );
}

#[test]
fn test28_no_array_field_lets_a_non_finite_number_through() {
    // Every array field of the format, each with `X` where a number goes: with `nan`,
    // `inf` or `-inf` there, the scene is refused with the line of the array and its
    // field. (Triangle normals and uvs were accepted and rendered until issue 37.)
    const VIEW: &str = "[camera.view]\nvrp = [0, 0, 0]\nvpn = [0, 0, 1]\nvup = [0, 1, 0]\ne = 1\nwindow = { left = -1, right = 1, bottom = -1, top = 1 }\n";
    const RENDER: &str = "[render]\nwidth = 8\nheight = 8\n";
    let look_at = "[camera.look_at]\nfrom = [0, 0, -5]\nat = [0, 0, 0]\nup = [0, 1, 0]\nfov = 40\n";
    let povray = "[camera.povray]\nlocation = [0, 0, -5]\ndirection = [0, 0, 1]\nright = [1.33, 0, 0]\nup = [0, 1, 0]\n";
    let view = |field: &str| {
        let (key, _) = field.split_once(" = ").unwrap();
        let line = VIEW.lines().find(|l| l.starts_with(key)).unwrap();
        format!("{}{RENDER}", VIEW.replace(line, field))
    };
    let with = |camera: &str, field: &str| {
        let (key, _) = field.split_once(" = ").unwrap();
        let line = camera.lines().find(|l| l.starts_with(key)).unwrap();
        format!("{}{RENDER}", camera.replace(line, field))
    };
    let scene = |rest: &str| format!("{VIEW}{RENDER}{rest}\n");
    let tri = "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 1], [1, 0, 1], [0, 1, 1]]\n";
    let cases: Vec<(String, &str)> = vec![
        (view("vrp = [0, X, 0]"), "camera.view"),
        (view("vpn = [0, 0, X]"), "camera.view"),
        (view("vup = [X, 1, 0]"), "camera.view"),
        (with(look_at, "from = [0, X, -5]"), "camera.look_at"),
        (with(look_at, "at = [X, 0, 0]"), "camera.look_at"),
        (with(look_at, "up = [0, X, 0]"), "camera.look_at"),
        (with(povray, "location = [0, 0, X]"), "camera.povray"),
        (with(povray, "direction = [0, X, 1]"), "camera.povray"),
        (with(povray, "right = [X, 0, 0]"), "camera.povray"),
        (with(povray, "up = [0, X, 0]"), "camera.povray"),
        (scene("background = [0, X, 0]"), "render.background"),
        (scene("ambient_light = [X, 1, 1]"), "render.ambient_light"),
        (scene("[[lights]]\nposition = [0, X, 0]"), "lights[0].position"),
        (scene("[[lights]]\ntype = \"directional\"\ndirection = [0, X, 0]"), "lights[0]"),
        (scene("[[lights]]\nposition = [0, 1, 0]\ncolor = [1, X, 1]"), "lights[0].color"),
        (scene("[materials.m]\ncolor = [1, 1, X]"), "materials.m.color"),
        (scene("[materials.m]\nradiance = [X, 1, 1]"), "materials.m"),
        (scene("[[objects]]\ntype = \"sphere\"\ntransform = [{ translate = [0, X, 0] }]"), "objects[0].transform[0]"),
        (scene("[[objects]]\ntype = \"sphere\"\ntransform = [{ rotate = { axis = [0, X, 0], degrees = 30 } }]"), "objects[0].transform[0]"),
        (scene("[[objects]]\ntype = \"sphere\"\ntransform = [{ scale = [1, X, 1] }]"), "objects[0].transform[0]"),
        (scene("[[objects]]\ntype = \"sphere\"\ntransform = [{ matrix = [[1, 0, 0], [0, 1, 0], [0, 0, X], [0, 0, 0]] }]"), "objects[0].transform[0]"),
        (scene("[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 1], [1, X, 1], [0, 1, 1]]"), "objects[0].vertices"),
        (scene(&format!("{tri}normals = [[0, 0, 1], [0, 0, 1], [0, X, 1]]")), "objects[0].normals"),
        (scene(&format!("{tri}uvs = [[0, 0], [1, X], [0, 1]]")), "objects[0].uvs"),
    ];
    let mut wrong = Vec::new();
    for (template, field) in &cases {
        for x in ["nan", "inf", "-inf"] {
            let text = template.replace('X', x);
            let line = 1 + text.lines().position(|l| l.contains(x)).unwrap();
            match load(&text) {
                Ok(_) => wrong.push(format!("{field} = {x}: accepted")),
                Err(e) if e.line != line || !e.field.contains(field) || e.column < 1 => wrong
                    .push(format!("{field} = {x}: refused at line {}, field {} (expected line {line}, a field naming {field}): {e}", e.line, e.field)),
                Err(_) => {}
            }
        }
    }
    assert!(wrong.is_empty(), "non-finite numbers not refused where they are written (renderer/src/scene/*_desc.rs, nodes.rs):\n{}", wrong.join("\n"));
}
