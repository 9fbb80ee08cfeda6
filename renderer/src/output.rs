//! Writing images: 8-bit sRGB PNG (or another device mapping) and 32-bit float linear EXR
//! with optional geometry channels. Files are written to a temporary name beside the
//! target and renamed into place, so a failure never leaves a half-written output.

use crate::image::Image;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// How linear intensities map to the 8-bit device range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ToneMap {
    /// Clamp to [0, 1], then the sRGB transfer curve.
    #[default]
    Srgb,
    /// Clamp to [0, 1], linear.
    Clamp,
    /// Rescale the image's min..max to [0, 1], linear.
    #[value(alias = "minmax")]
    MinMax,
}

/// The sRGB transfer curve (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Buckets of [0, 1] for [`srgb8`]'s first guess. The steps are at least 3·10⁻⁴ apart (the
/// linear segment's), more than a bucket's width, so at most one step lies inside a bucket.
const SRGB_BUCKETS: usize = 4096;

/// What [`srgb8`] reads, built once.
struct SrgbTable {
    /// The 255 linear values at which the nearest 8-bit sRGB code changes (the decoded
    /// half-codes, computed in f64), ascending.
    steps: [f32; 255],
    /// For each bucket `b`, the code of its lower end `b / SRGB_BUCKETS`: the number of
    /// steps at or below it.
    codes: [u8; SRGB_BUCKETS + 1],
}

fn srgb_table() -> &'static SrgbTable {
    static TABLE: std::sync::LazyLock<SrgbTable> = std::sync::LazyLock::new(|| {
        let steps: [f32; 255] = std::array::from_fn(|k| {
            let e = (k as f64 + 0.5) / 255.0;
            let linear = if e <= 0.04045 {
                e / 12.92
            } else {
                ((e + 0.055) / 1.055).powf(2.4)
            };
            linear as f32
        });
        let codes = std::array::from_fn(|b| {
            let lower = b as f32 / SRGB_BUCKETS as f32;
            steps.partition_point(|&t| t <= lower) as u8
        });
        SrgbTable { steps, codes }
    });
    &TABLE
}

/// The 8-bit sRGB code of a linear value in [0, 1]: the code k whose encoded value k/255
/// is nearest to the exact sRGB encoding of `x`, that is the number of steps
/// (`SrgbTable::steps`) at or below `x`. The code of `x`'s bucket's lower end is looked up
/// and then advanced past the steps between that end and `x` (at most one, rarely any):
/// the same count as a search of all 255, which took eight dependent comparisons per
/// channel (7 % of a 1920 × 1440 Whitted frame's time). Below 0 (and NaN) gives 0, above 1
/// gives 255.
pub fn srgb8(x: f32) -> u8 {
    let table = srgb_table();
    // x·4096 is exact (a power of two), so the bucket's lower end is never above x.
    let b = ((x * SRGB_BUCKETS as f32) as usize).min(SRGB_BUCKETS);
    let mut k = table.codes[b] as usize;
    while k < table.steps.len() && table.steps[k] <= x {
        k += 1;
    }
    k as u8
}

/// 8-bit RGB pixels of `img` under a device mapping.
pub fn to_rgb8(img: &Image, map: ToneMap) -> Vec<u8> {
    use rayon::prelude::*;
    let (lo, hi) = match map {
        ToneMap::MinMax => img
            .rgb
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            }),
        _ => (0.0, 1.0),
    };
    let span = if hi > lo { hi - lo } else { 1.0 };
    img.rgb
        .par_iter()
        .map(|&v| {
            let x = ((v - lo) / span).clamp(0.0, 1.0);
            if map == ToneMap::Srgb {
                srgb8(x)
            } else {
                (x * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
            }
        })
        .collect()
}

/// Temp files being written, so a signal handler can remove them ([`remove_temp_files`]).
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A fault for tests: milliseconds to wait after the temp file is created and before it is
/// written, so a test can deliver a signal while an output is being written (the CLI sets
/// it from `RENDERER_FAULT_SLOW_WRITE_MS`). 0 in normal use.
pub static SLOW_WRITE_MS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Removes every temp file an interrupted write left (called from the CLI's SIGINT and
/// SIGTERM handler before it exits).
pub fn remove_temp_files() {
    let pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
    for p in pending.iter() {
        let _ = std::fs::remove_file(p);
    }
}

/// A temp file beside the output, registered for removal on a signal, and removed on drop
/// unless it was moved into place.
struct TempFile {
    path: PathBuf,
    file: std::fs::File,
    kept: bool,
}

impl TempFile {
    fn create(out: &Path) -> Result<TempFile> {
        let path = temp_path(out);
        let mut pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
        let open = || {
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
        };
        let file = match open() {
            // Left by an earlier process that had our PID: it is not being written now.
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let _ = std::fs::remove_file(&path);
                open()
            }
            r => r,
        }
        .with_context(|| format!("cannot create {}", path.display()))?;
        pending.push(path.clone());
        Ok(TempFile {
            path,
            file,
            kept: false,
        })
    }

    /// Makes the data durable and moves the file over `out`.
    fn persist(mut self, out: &Path) -> Result<()> {
        self.file
            .sync_all()
            .with_context(|| format!("cannot write {} (sync)", self.path.display()))?;
        std::fs::rename(&self.path, out)
            .with_context(|| format!("cannot move the output into {}", out.display()))?;
        self.kept = true;
        // The rename itself is durable once the directory is synced (best effort: some
        // file systems do not let a directory be opened for syncing).
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            if let Ok(d) = std::fs::File::open(dir) {
                let _ = d.sync_all();
            }
        }
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.kept {
            let _ = std::fs::remove_file(&self.path);
        }
        let mut pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
        pending.retain(|p| p != &self.path);
    }
}

/// Writes a PNG or EXR, by the file's extension. The image goes to a temp file beside the
/// output (`.NAME.PID.tmp`), which is flushed, synced and checked, then renamed over the
/// output: an existing output is replaced only by a complete new file. On any error the
/// temp file is removed. Temp files of dead processes, left by a crash or a power loss,
/// are removed first.
pub fn write(img: &Image, path: &Path, map: ToneMap) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if ext != "png" && ext != "exr" {
        bail!(
            "{}: unknown output format (use .png or .exr)",
            path.display()
        );
    }
    check_folder(path)?;
    remove_stale_temp_files(path);
    let tmp = TempFile::create(path)?;
    let delay = SLOW_WRITE_MS.load(std::sync::atomic::Ordering::Relaxed);
    if delay > 0 {
        std::thread::sleep(std::time::Duration::from_millis(delay));
    }
    let mut w = std::io::BufWriter::new(&tmp.file);
    match ext.as_str() {
        "png" => encode_png(img, &mut w, map),
        _ => encode_exr(img, &mut w),
    }
    .with_context(|| format!("cannot write {}", tmp.path.display()))?;
    // The final flush's error must not be lost when the writer is dropped.
    w.into_inner()
        .map_err(|e| e.into_error())
        .with_context(|| format!("cannot write {}", tmp.path.display()))?;
    tmp.persist(path)
}

/// Checks that the folder an output goes into exists (the CLI calls this before it
/// renders), so the error names that folder rather than the temp file beside the output.
pub fn check_folder(path: &Path) -> Result<()> {
    let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) else {
        return Ok(()); // The working directory.
    };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => bail!("{}: {} is not a folder", path.display(), dir.display()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "{}: the folder {} does not exist (create it first)",
            path.display(),
            dir.display()
        ),
        Err(e) => bail!(
            "{}: cannot use the folder {}: {e}",
            path.display(),
            dir.display()
        ),
    }
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Removes `.NAME.PID.tmp` files beside `path` whose process no longer runs (Linux: no
/// `/proc/PID`; elsewhere none are removed).
fn remove_stale_temp_files(path: &Path) {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.");
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".tmp"))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

fn encode_png(img: &Image, w: &mut impl std::io::Write, map: ToneMap) -> Result<()> {
    encode_png_rgb8(w, img.width, img.height, &to_rgb8(img, map))
}

/// Encodes 8-bit RGB pixels (`width · height · 3` bytes, rows top to bottom) as a PNG, with
/// the `png` crate's fast compression (fdeflate) and adaptive filtering. Its balanced
/// compression (zlib level 6, as libpng and POV-Ray write) made files 20-42 % smaller
/// but took 7-15 times as long: 0.11-0.24 s of one core for a 1920 x 1440 image, 10-15 %
/// of a Whitted render's whole CPU time (renderer/docs/performance.md, "PNG output").
pub fn encode_png_rgb8(
    w: &mut impl std::io::Write,
    width: u32,
    height: u32,
    rgb8: &[u8],
) -> Result<()> {
    anyhow::ensure!(
        rgb8.len() as u64 == width as u64 * height as u64 * 3,
        "{} bytes of RGB for a {width} × {height} image",
        rgb8.len()
    );
    let mut enc = png::Encoder::new(w, width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    enc.set_filter(png::Filter::Adaptive);
    let mut writer = enc.write_header()?;
    writer.write_image_data(rgb8)?;
    writer.finish()?;
    Ok(())
}

/// Writes a 32-bit float, linear EXR; with AOVs adds Z, N.X/Y/Z, P.X/Y/Z and objectId.
pub fn write_exr(img: &Image, path: &Path) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    encode_exr(img, &mut w).with_context(|| format!("cannot write {}", path.display()))?;
    w.into_inner()
        .map_err(|e| e.into_error())
        .and_then(|f| f.sync_all())
        .with_context(|| format!("cannot write {}", path.display()))
}

fn encode_exr(img: &Image, w: &mut (impl std::io::Write + std::io::Seek)) -> Result<()> {
    use exr::prelude::*;
    let (wd, h) = (img.width as usize, img.height as usize);
    let chan = |name: &str, data: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(data));
    let plane = |src: &[f32], stride: usize, k: usize| -> Vec<f32> {
        src.iter().skip(k).step_by(stride).copied().collect()
    };
    let mut channels = vec![
        chan("R", plane(&img.rgb, 3, 0)),
        chan("G", plane(&img.rgb, 3, 1)),
        chan("B", plane(&img.rgb, 3, 2)),
    ];
    if let Some(a) = &img.aov {
        channels.push(chan("Z", a.z.clone()));
        for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
            channels.push(chan(&format!("N.{axis}"), plane(&a.n, 3, k)));
            channels.push(chan(&format!("P.{axis}"), plane(&a.p, 3, k)));
        }
        channels.push(chan("objectId", a.object_id.clone()));
    }
    let layer = Layer::new(
        (wd, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_buffered(w)?;
    Ok(())
}

#[cfg(test)]
mod srgb_tests {
    use super::*;

    /// The search of all 255 steps that [`srgb8`] shortcuts.
    fn searched(x: f32) -> u8 {
        srgb_table().steps.partition_point(|&t| t <= x) as u8
    }

    #[test]
    fn the_bucketed_code_is_the_searched_one() {
        let mut xs = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            2.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            f32::EPSILON,
        ];
        // Each step and its neighbours, where the code changes.
        for &t in &srgb_table().steps {
            xs.extend([t.next_down(), t, t.next_up()]);
        }
        // Each bucket's ends.
        for b in 0..=SRGB_BUCKETS {
            let e = b as f32 / SRGB_BUCKETS as f32;
            xs.extend([e.next_down(), e, e.next_up()]);
        }
        // A sweep of the float bit patterns of [0, 1].
        xs.extend((0..=1.0f32.to_bits()).step_by(1009).map(f32::from_bits));
        for x in xs {
            assert_eq!(
                srgb8(x),
                searched(x),
                "srgb8({x:e}) (bits {:#x}) differs from the search of all steps: see SrgbTable::codes",
                x.to_bits()
            );
        }
    }
}

#[cfg(test)]
mod write_tests {
    use super::*;

    /// A writer that fails once `limit` bytes have been written (a full disk).
    struct Full {
        data: Vec<u8>,
        pos: u64,
        limit: usize,
    }

    impl std::io::Write for Full {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            if self.data.len() + b.len() > self.limit {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::StorageFull,
                    "disk full",
                ));
            }
            self.data.extend_from_slice(b);
            self.pos += b.len() as u64;
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl std::io::Seek for Full {
        fn seek(&mut self, p: std::io::SeekFrom) -> std::io::Result<u64> {
            if let std::io::SeekFrom::Start(n) = p {
                self.pos = n;
            }
            Ok(self.pos)
        }
    }

    fn image() -> Image {
        let (w, h) = (64u32, 48u32);
        let rgb = (0..w * h * 3)
            .map(|k| ((k * 7919) % 1000) as f32 / 1000.0)
            .collect();
        Image {
            samples: 0,
            width: w,
            height: h,
            rgb,
            aov: None,
            non_finite: 0,
            moments: None,
        }
    }

    #[test]
    fn a_full_disk_is_an_error_for_every_format() {
        let img = image();
        type Encode = fn(&Image, &mut std::io::BufWriter<Full>) -> Result<()>;
        let formats: [(&str, Encode); 2] = [
            ("PNG", |img, w| encode_png(img, w, ToneMap::Srgb)),
            ("EXR", |img, w| encode_exr(img, w)),
        ];
        for (name, encode) in formats {
            // Any room short of the whole file must fail; the whole file's room must not.
            let write = |limit: usize| {
                let mut w = std::io::BufWriter::new(Full {
                    data: Vec::new(),
                    pos: 0,
                    limit,
                });
                encode(&img, &mut w).and_then(|()| {
                    w.into_inner()
                        .map(|f| f.data.len())
                        .map_err(|e| e.into_error().into())
                })
            };
            let size = write(usize::MAX).expect("room enough");
            for limit in [0, 100, size / 2, size - 1] {
                assert!(
                    write(limit).is_err(),
                    "{name} of {size} bytes with {limit} bytes free must fail"
                );
            }
            assert_eq!(write(size).ok(), Some(size), "{name} with just enough room");
        }
    }
}

/// A float image read from an EXR: channels by name, each `width × height`, top row first.
#[derive(Clone, Debug)]
pub struct ExrImage {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Channel name and samples (half and uint channels converted to f32).
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    /// The samples of a channel.
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Reads the first layer of an EXR file, every channel as f32.
pub fn read_exr(path: &Path) -> Result<ExrImage> {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let size = img.layer_data.size;
    let channels = img
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v: Vec<f32> = c.sample_data.values_as_f32().collect();
            (c.name.to_string(), v)
        })
        .collect();
    Ok(ExrImage {
        width: size.0,
        height: size.1,
        channels,
    })
}
