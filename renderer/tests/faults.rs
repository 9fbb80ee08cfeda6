//! Ordinary faults never lose a file or leave one behind: a full disk, an output path that
//! cannot be renamed into, SIGINT or SIGTERM while the output is written, temp files of a
//! crashed run, a thread count the process may not start, and non-finite pixels. Each runs
//! the built binary in a child process (a shell sets the resource limit), and checks the
//! exit status, the existing output (unchanged, byte for byte) and the folder (no
//! `.NAME.PID.tmp` left).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_renderer");
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("renderer-faults-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A noisy scene (path traced at 1 spp), so its PNG does not compress to almost nothing.
fn noisy_scene() -> String {
    format!("{ROOT}/conformance/scenes/mitsuba/mi_cornell.toml")
}

fn temp_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// After a failed write: the existing output still holds "OLD", and no temp file is left.
#[track_caller]
fn assert_untouched(dir: &Path, out: &Path, case: &str) {
    assert_eq!(
        std::fs::read(out).unwrap(),
        b"OLD",
        "{case}: the existing output changed"
    );
    assert!(
        temp_files(dir).is_empty(),
        "{case}: left {:?}",
        temp_files(dir)
    );
}

fn sh(script: &str) -> Output {
    Command::new("sh").arg("-c").arg(script).output().unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn test01_a_full_disk_fails_and_keeps_the_old_output_for_every_format() {
    for ext in ["png", "exr"] {
        let dir = scratch(&format!("full-{ext}"));
        let out = dir.join(format!("out.{ext}"));
        std::fs::write(&out, b"OLD").unwrap();
        // ulimit -f: the file may not grow past 4 KiB, as on a full disk (EFBIG instead of
        // ENOSPC); SIGXFSZ is ignored so the write fails instead of killing the process.
        let o = sh(&format!(
            "trap '' XFSZ; ulimit -f 8; exec {BIN} render {} -o {} --size 256x256 --spp 1",
            noisy_scene(),
            out.display()
        ));
        assert!(
            !o.status.success(),
            "{ext}: a write that cannot complete exited 0: {}",
            text(&o)
        );
        assert!(text(&o).contains("cannot write"), "{ext}: {}", text(&o));
        assert_untouched(&dir, &out, ext);
    }
}

#[test]
fn test02_a_failed_rename_leaves_no_temp_file() {
    let dir = scratch("rename");
    // The output path is a folder: the temp file is written, and the rename fails.
    let out = dir.join("out.png");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep"), b"x").unwrap();
    let o = Command::new(BIN)
        .args([
            "render",
            &format!("{ROOT}/renderer/scenes/sphere.toml"),
            "-o",
        ])
        .arg(&out)
        .args(["--size", "8x6"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("cannot move the output into"),
        "{}",
        text(&o)
    );
    assert!(
        out.join("keep").exists(),
        "the folder in the way was touched"
    );
    assert!(temp_files(&dir).is_empty(), "left {:?}", temp_files(&dir));
}

#[test]
fn test03_a_signal_while_writing_removes_the_temp_file() {
    for signal in ["INT", "TERM"] {
        let dir = scratch(&format!("signal-{signal}"));
        let out = dir.join("out.png");
        std::fs::write(&out, b"OLD").unwrap();
        let child = Command::new(BIN)
            .args([
                "render",
                &format!("{ROOT}/renderer/scenes/sphere.toml"),
                "-o",
            ])
            .arg(&out)
            .args(["--size", "8x6"])
            .env("RENDERER_FAULT_SLOW_WRITE_MS", "20000")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for the temp file: the write has begun and is held open.
        let t0 = Instant::now();
        while temp_files(&dir).is_empty() {
            assert!(
                t0.elapsed() < Duration::from_secs(30),
                "no temp file appeared"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let k = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(k.success());
        let o = child.wait_with_output().unwrap();
        assert!(!o.status.success(), "SIG{signal}: exited 0");
        assert_untouched(&dir, &out, &format!("SIG{signal}"));
    }
}

#[test]
fn test04_temp_files_of_dead_processes_are_removed_and_live_ones_kept() {
    let dir = scratch("stale");
    let out = dir.join("out.png");
    // PIDs above Linux's largest pid_max (2^22) never belong to a running process.
    let dead = dir.join(".out.png.4194305.tmp");
    let live = dir.join(format!(".out.png.{}.tmp", std::process::id()));
    let other = dir.join(".other.png.4194305.tmp");
    for f in [&dead, &live, &other] {
        std::fs::write(f, b"partial").unwrap();
    }
    let o = Command::new(BIN)
        .args([
            "render",
            &format!("{ROOT}/renderer/scenes/sphere.toml"),
            "-o",
        ])
        .arg(&out)
        .args(["--size", "8x6"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(!dead.exists(), "a dead process's temp file was kept");
    assert!(live.exists(), "a running process's temp file was removed");
    assert!(other.exists(), "another output's temp file was removed");
}

#[test]
fn test05_a_thread_count_the_process_cannot_start_is_an_error() {
    // 1000 threads of 2 MiB stacks do not fit in 400 MB of address space.
    let o = sh(&format!(
        "ulimit -v 400000; exec {BIN} render {ROOT}/renderer/scenes/sphere.toml -o {}/t.png --threads 1000 --size 8x6",
        scratch("threads").display()
    ));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("--threads 1000: cannot start 1000 threads"),
        "{}",
        text(&o)
    );
    assert!(!text(&o).contains("panicked"), "{}", text(&o));
}

#[test]
fn test06_non_finite_pixels_are_reported_and_nothing_is_written() {
    let dir = scratch("nonfinite");
    // Two lights near the largest finite f32, at the eye, on a fully diffuse sphere: their
    // sum overflows to infinity at the pixels facing them.
    let scene = dir.join("hot.toml");
    std::fs::write(
        &scene,
        r#"
[camera.look_at]
from = [0, 0, -4]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 40
[render]
width = 8
height = 6
[[lights]]
position = [0, 0, -4]
color = [3e38, 3e38, 3e38]
[[lights]]
position = [0, 0, -4]
color = [3e38, 3e38, 3e38]
[materials.m]
diffuse = 1
[[objects]]
type = "sphere"
material = "m"
"#,
    )
    .unwrap();
    let out = dir.join("out.png");
    let o = Command::new(BIN)
        .args(["render"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        !o.status.success(),
        "non-finite pixels exited 0: {}",
        text(&o)
    );
    assert!(text(&o).contains("non-finite"), "{}", text(&o));
    assert!(!out.exists(), "an image with non-finite pixels was written");
}
