//! Inputs that look legitimate but used to crash or hang: thousands of transparent
//! surfaces, facing mirrors at a deep trace level, long chains of definitions, a definition
//! that places itself without being placed, and a path integrator told never to stop.
//! Each runs the binary in a child process with a time limit, so a stack overflow (an
//! abort) or a hang fails the test instead of the test binary. The limits are documented
//! in renderer/docs/robustness.md.

use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_renderer");

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("renderer-limits-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const HEAD: &str = r#"
[camera.look_at]
from = [0, 0, -5]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 30
[render]
width = 16
height = 12
"#;

/// Renders `text` (written to NAME.toml) with a 120 s limit; returns the output.
fn render(name: &str, text: &str) -> Output {
    let dir = scratch(name);
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let mut child = Command::new(BIN)
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("out.png"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(120) {
            child.kill().unwrap();
            panic!("{name}: the render did not finish within 120 s (a hang)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Requires a clean success (no signal: an abort from a stack overflow is a signal).
fn assert_renders(name: &str, o: &Output) {
    assert!(
        o.status.success(),
        "{name}: expected a finished render, got {:?}: {}",
        o.status,
        text(o)
    );
}

/// Requires a located error (exit 2) whose message contains each of `says`.
fn assert_refused(name: &str, o: &Output, says: &[&str]) {
    assert_eq!(
        o.status.code(),
        Some(2),
        "{name}: {:?}: {}",
        o.status,
        text(o)
    );
    for s in says {
        assert!(
            text(o).contains(s),
            "{name}: the error should say {s:?}: {}",
            text(o)
        );
    }
}

#[test]
fn test01_ten_thousand_transparent_slabs_render() {
    let mut t = format!("{HEAD}max_depth = 5\n[[lights]]\nposition = [0, 5, -5]\n[materials.clear]\ntransmit = 1\nior = 1\n");
    for k in 0..10_000 {
        t += &format!(
            "[[objects]]\ntype = \"box\"\nmaterial = \"clear\"\ntransform = [{{ scale = [1, 1, 0.0001] }}, {{ translate = [0, 0, {}] }}]\n",
            k as f64 * 1e-3
        );
    }
    assert_renders("slabs", &render("slabs", &t));
}

const MIRRORS: &str = r#"
[camera.look_at]
from = [0, 0, -0.5]
at = [0, 0, 1]
up = [0, 1, 0]
fov = 30
[render]
width = 16
height = 12
max_depth = DEPTH
[[lights]]
position = [0, 0.5, 0]
[materials.mirror]
color = [0.1, 0.1, 0.1]
reflection = 1
[[objects]]
type = "plane"
material = "mirror"
transform = [{ rotate = { axis = [1, 0, 0], degrees = -90 } }, { translate = [0, 0, 1] }]
[[objects]]
type = "plane"
material = "mirror"
transform = [{ rotate = { axis = [1, 0, 0], degrees = 90 } }, { translate = [0, 0, -1] }]
"#;

#[test]
fn test02_facing_mirrors_at_the_deepest_trace_level_render_and_deeper_is_refused() {
    assert_renders(
        "mirrors",
        &render("mirrors", &MIRRORS.replace("DEPTH", "256")),
    );
    let o = render("mirrors_deep", &MIRRORS.replace("DEPTH", "3000"));
    assert_refused(
        "mirrors_deep",
        &o,
        &["mirrors_deep.toml:10:1: render.max_depth", "limit of 256"],
    );
}

fn chain(n: usize) -> String {
    let mut t = format!("{HEAD}[defs.d0]\ntype = \"sphere\"\n");
    for k in 1..n {
        t += &format!("[defs.d{k}]\ntype = \"instance\"\nof = \"d{}\"\n", k - 1);
    }
    t + &format!("[[objects]]\ntype = \"instance\"\nof = \"d{}\"\n", n - 1)
}

#[test]
fn test03_definition_chains_deeper_than_the_limit_are_refused() {
    assert_renders("chain_ok", &render("chain_ok", &chain(63)));
    for n in [300, 100_000] {
        let o = render("chain", &chain(n));
        assert_refused(
            "chain",
            &o,
            &["definitions nest deeper than 64 levels", "defs.d"],
        );
    }
}

#[test]
fn test04_a_definition_that_places_itself_is_refused_even_unplaced() {
    let t = format!(
        "{HEAD}[defs.a]\ntype = \"instance\"\nof = \"b\"\n[defs.b]\ntype = \"group\"\nchildren = [{{ type = \"instance\", of = \"a\" }}]\n[[objects]]\ntype = \"sphere\"\n"
    );
    let o = render("cycle", &t);
    assert_refused("cycle", &o, &["defs.b.of", "defs.a → defs.b → defs.a"]);
}

#[test]
fn test05_a_path_told_never_to_stop_still_finishes() {
    let cornell = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../conformance/scenes/mitsuba/mi_cornell.toml"
    ))
    .unwrap();
    let t = cornell
        .replace("max_depth = 6", "max_depth = 256")
        .replace("[render]", "[render]\nrr_depth = 4294967295");
    assert!(
        t.contains("max_depth = 256"),
        "mi_cornell.toml changed its max_depth"
    );
    assert_renders("path", &render("path", &t));
    let o = render(
        "path_deep",
        &t.replace("max_depth = 256", "max_depth = 4294967295"),
    );
    assert_refused("path_deep", &o, &["render.max_depth", "limit of 256"]);
}
