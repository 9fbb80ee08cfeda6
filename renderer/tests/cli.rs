//! The command line: `--spp` and `--size` replace the scene's settings and are validated
//! like them; `--map` accepts the spelling the docs use; errors exit non-zero and leave no
//! file behind.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sphere.toml");

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("renderer-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_renderer"))
        .args(args)
        .output()
        .expect("the renderer binary runs")
}

fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    (be(16), be(20))
}

/// (args after `render SCENE -o OUT`, expected success, text the output must contain)
fn check(name: &str, extra: &[&str], ok: bool, says: &str) -> PathBuf {
    let dir = scratch(name);
    let out = dir.join("out.png");
    let mut args = vec!["render", SCENE, "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run(&args);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(o.status.success(), ok, "renderer {args:?}: {text}");
    assert!(
        text.contains(says),
        "renderer {args:?} should say {says:?}: {text}"
    );
    if !ok {
        assert!(!out.exists(), "a failed render left {}", out.display());
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "leftovers in {}",
            dir.display()
        );
    }
    out
}

#[test]
fn test01_size_and_spp_replace_the_scene_settings() {
    let out = check(
        "size",
        &["--size", "20x10", "--spp", "3"],
        true,
        "20x10 px, 3 spp",
    );
    assert_eq!(png_size(&out), (20, 10));
    let out = check("size-upper", &["--size", "7X5"], true, "7x5 px");
    assert_eq!(png_size(&out), (7, 5));
}

#[test]
fn test02_bad_overrides_are_refused_like_scene_fields() {
    check(
        "w0",
        &["--size", "0x10"],
        false,
        "'0x10': width: must be at least 1",
    );
    check(
        "h0",
        &["--size", "10x0"],
        false,
        "'10x0': height: must be at least 1",
    );
    check(
        "big",
        &["--size", "1000000x1000000"],
        false,
        "more than the limit of 134217728",
    );
    check("shape", &["--size", "640"], false, "expected WIDTHxHEIGHT");
    check(
        "neg",
        &["--size=-4x3"],
        false,
        "is not a whole number of pixels",
    );
    check(
        "spp0",
        &["--spp", "0"],
        false,
        "--spp 0: must be at least 1",
    );
}

#[test]
fn test03_map_accepts_minmax_and_min_max() {
    for m in ["minmax", "min-max", "clamp", "srgb"] {
        check(
            &format!("map-{m}"),
            &["--map", m, "--size", "4x3"],
            true,
            "4x3 px",
        );
    }
}

#[test]
fn test04_every_option_of_render_help_is_documented() {
    // renderer/docs/cli.md lists every long option that `renderer render --help` prints.
    let doc = include_str!("../docs/cli.md");
    let o = run(&["render", "--help"]);
    assert!(o.status.success(), "renderer render --help failed");
    let help = String::from_utf8_lossy(&o.stdout);
    let mut options: Vec<String> = help
        .split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == ']')
        .filter(|w| w.starts_with("--") && w.len() > 2)
        .map(|w| {
            w.split(['=', '<'])
                .next()
                .unwrap()
                .trim_end_matches('.')
                .to_string()
        })
        .collect();
    options.sort();
    options.dedup();
    assert!(
        options.len() >= 8,
        "found only {options:?} in `renderer render --help`:\n{help}"
    );
    // The first column of the option table: one row per option.
    let rows: Vec<&str> = doc
        .lines()
        .filter_map(|l| l.strip_prefix('|')?.split('|').next())
        .collect();
    let missing: Vec<&String> = options
        .iter()
        .filter(|opt| !rows.iter().any(|r| r.contains(&format!("`{opt}`"))))
        .collect();
    assert!(
        missing.is_empty(),
        "`renderer render --help` shows {missing:?}, which renderer/docs/cli.md does not \
document: add a row to its option table (value, default, meaning)"
    );
}

fn stderr_of(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn test05_threads_zero_is_every_core_and_too_many_are_refused() {
    check(
        "threads0",
        &["--threads", "0", "--size", "8x6"],
        true,
        "8x6 px",
    );
    // Far more threads than any machine's cores: refused before the scene is read, not
    // 100,000 operating-system threads started.
    let t0 = std::time::Instant::now();
    check(
        "threads-many",
        &["--threads", "100000"],
        false,
        "100000 threads is more than the limit of 1024",
    );
    assert!(
        t0.elapsed().as_secs() < 30,
        "refusing --threads 100000 took {:?}",
        t0.elapsed()
    );
    check(
        "threads-max",
        &["--threads", "1024", "--size", "8x6"],
        true,
        "8x6 px",
    );
}

#[test]
fn test06_a_missing_output_folder_is_named_before_the_render() {
    let dir = scratch("nofolder");
    let out = dir.join("not/there/out.png");
    let o = run(&["render", SCENE, "-o", out.to_str().unwrap()]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "the folder {} does not exist",
            dir.join("not/there").display()
        )),
        "the error should name the missing folder: {err}"
    );
    assert!(
        !err.contains(".tmp"),
        "the error names the temp file: {err}"
    );
    assert!(
        !err.contains(" px, "),
        "the scene was rendered before the folder was checked: {err}"
    );
}

#[test]
fn test07_a_missing_scene_file_has_no_made_up_location() {
    let dir = scratch("noscene");
    let o = run(&[
        "render",
        "nothere.toml",
        "-o",
        dir.join("out.png").to_str().unwrap(),
    ]);
    assert_eq!(
        stderr_of(&o).trim_end(),
        "error: nothere.toml: cannot read the scene file: No such file or directory (os error 2)"
    );
}

#[test]
fn test08_progress_plain_prints_a_line_per_tenth_and_auto_is_silent_in_a_pipe() {
    let dir = scratch("progress");
    let out = dir.join("out.png");
    let args = |mode: &'static str| {
        [
            "render",
            SCENE,
            "-o",
            out.to_str().unwrap(),
            "--size",
            "16x40",
            "--progress",
            mode,
        ]
        .map(String::from)
    };
    let o = Command::new(env!("CARGO_BIN_EXE_renderer"))
        .args(args("plain"))
        .output()
        .unwrap();
    let err = stderr_of(&o);
    assert!(o.status.success(), "{err}");
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("progress: "))
        .collect();
    let expected: Vec<String> = (1..=10)
        .map(|k| format!("progress: {} % ({}/40 rows), ", k * 10, k * 4))
        .collect();
    assert_eq!(lines.len(), 10, "one line per tenth of the rows: {err}");
    for (line, want) in lines.iter().zip(&expected) {
        assert!(
            line.starts_with(want.as_str()),
            "{line:?} should start {want:?}: {err}"
        );
    }
    // The test's stderr is a pipe: auto shows nothing, and neither does none.
    for mode in ["auto", "none"] {
        let o = Command::new(env!("CARGO_BIN_EXE_renderer"))
            .args(args(mode))
            .output()
            .unwrap();
        let err = stderr_of(&o);
        assert!(o.status.success(), "{err}");
        assert_eq!(
            err.lines().count(),
            1,
            "--progress {mode} into a pipe: {err}"
        );
    }
}
