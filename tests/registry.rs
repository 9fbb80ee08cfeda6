//! A reference is its folder plus one registry line: a fake reference, registered here
//! and nowhere else, appears in the gate's selection and verdicts (with a verdict of its
//! own beside POV-Ray's on the same scene, and their disagreement), in the waivers (its
//! checks accepted, others refused), and in the report (summary, legend, scene rows and
//! anchors, verdicts by scene, results.json, the text table), without an edit to the
//! gate, the report, the waivers or the command line.

use anyhow::Result;
use conformance::catalog::Entry;
use conformance::checked::{abs_difference, worst_pixels, Checked, Figure, Pixel};
use conformance::gate::{by_scene, check_all, judge};
use conformance::images::image_of;
use conformance::manifest::Manifest;
use conformance::reference::{ExportOptions, Reference, RegenOptions, WorstPlot};
use conformance::registry::Registry;
use conformance::verdict::Verdict;
use conformance::waivers::Waivers;
use renderer::render::Image;
use renderer::scene::Scene;
use std::path::Path;

/// A reference that checks the classic catalog's `prim_sphere_*` scenes against a grey
/// image: it fails every scene in its one check, `grey`.
struct Fake;

const GREY: f32 = 0.5;

struct FakeOutcome {
    scene: String,
    ours: Image,
    reference: Vec<f32>,
}

impl Checked for FakeOutcome {
    fn reference(&self) -> &str {
        "fake"
    }
    fn catalog(&self) -> &str {
        "povray"
    }
    fn scene(&self) -> &str {
        &self.scene
    }
    fn verdict(&self) -> Verdict {
        if self.checks()[0].1 {
            Verdict::Pass
        } else {
            Verdict::Fail
        }
    }
    fn checks(&self) -> Vec<(&'static str, bool)> {
        vec![("grey", self.ours.rgb == self.reference)]
    }
    fn metrics(&self) -> String {
        format!("fake metric: {} pixels", self.ours.rgb.len() / 3)
    }
    fn ours(&self) -> &Image {
        &self.ours
    }
    fn reference_rgb(&self) -> Option<&[f32]> {
        Some(&self.reference)
    }
    fn seconds(&self) -> f64 {
        0.0
    }
    fn worst(&self, n: usize) -> Vec<Pixel> {
        let d = abs_difference(&self.ours.rgb, &self.reference);
        worst_pixels(
            self.ours.width as usize,
            &self.ours.rgb,
            &self.reference,
            n,
            &|k| d[3 * k] as f64,
            &|_| "fake class".into(),
        )
    }
    fn worst_score(&self) -> f64 {
        7.0
    }
    fn figure(&self) -> Option<Figure> {
        Some(Figure {
            name: "fakefig",
            linear: abs_difference(&self.ours.rgb, &self.reference),
            png: vec![0; self.ours.rgb.len()],
        })
    }
}

impl Reference for Fake {
    fn name(&self) -> &'static str {
        "fake"
    }
    fn title(&self) -> &'static str {
        "Fake 1.0"
    }
    fn catalog(&self) -> &'static str {
        "povray"
    }
    fn covers(&self, entry: &Entry) -> Result<bool> {
        Ok(entry.name.starts_with("prim_sphere_"))
    }
    fn checks(&self) -> &'static [&'static str] {
        &["grey"]
    }
    fn how(&self) -> String {
        "a grey card (Fake)".into()
    }
    fn export(&self, _: &Scene, _: &str, _: &ExportOptions, _: &Path) -> Result<()> {
        anyhow::bail!("fake exports nothing")
    }
    fn regenerate(&self, _: &[Entry], _: &RegenOptions) -> Result<()> {
        anyhow::bail!("fake regenerates nothing")
    }
    fn check_regenerated(&self, _: &[Entry]) -> Result<Vec<String>> {
        Ok(Vec::new())
    }
    fn compare(&self, entry: &Entry, _: &Manifest) -> Result<Box<dyn Checked>> {
        let (scene, _) = conformance::catalog::load(entry)?;
        let (w, h) = (scene.settings.width, scene.settings.height);
        let ours = conformance::povray::harness::render_for_conformance(&scene);
        Ok(Box::new(FakeOutcome {
            scene: entry.name.clone(),
            reference: image_of(w, h, &vec![GREY; (w * h * 3) as usize]).rgb,
            ours,
        }))
    }
    fn legend(&self) -> String {
        "Fake scenes: FAKE-LEGEND.".into()
    }
    fn worst_plot(&self) -> WorstPlot {
        WorstPlot {
            title: "FAKE-PLOT",
            label: "fake",
            mark: None,
        }
    }
}

static FAKE: Fake = Fake;

const SCENE: &str = "prim_sphere_identity";

fn registry() -> Registry {
    Registry::committed().with(&FAKE).unwrap()
}

fn manifest() -> Manifest {
    Manifest::committed().unwrap()
}

#[test]
fn test01_a_registered_reference_selects_the_scenes_it_covers() {
    let r = registry();
    assert_eq!(r.names(), ["povray", "mitsuba", "oracle", "cycles", "fake"]);
    let mine = r.select("fake::").unwrap();
    assert!(!mine.is_empty());
    assert!(
        mine.iter()
            .all(|(x, e)| x.name() == "fake" && e.name.starts_with("prim_sphere_")),
        "{mine:?}"
    );
    // A scene's whole name selects it for every reference that checks it.
    let both: Vec<&str> = r
        .select(SCENE)
        .unwrap()
        .iter()
        .map(|(x, _)| x.name())
        .collect();
    assert_eq!(both, ["povray", "oracle", "fake"]);
    // The committed registry knows no fake, and a name is registered once.
    assert!(Registry::committed().select("fake::").is_err());
    assert!(r.with(&FAKE).is_err(), "two references named fake");
}

#[test]
fn test02_the_gate_judges_it_and_sees_the_references_disagree() {
    let r = registry();
    let judged = check_all(&r, SCENE, &manifest(), &Waivers::default()).unwrap();
    let got: Vec<(String, Verdict)> = judged
        .iter()
        .map(|j| (j.checked.reference().to_string(), j.verdict))
        .collect();
    assert_eq!(
        got,
        [
            ("povray".to_string(), Verdict::Pass),
            ("oracle".to_string(), Verdict::Pass),
            ("fake".to_string(), Verdict::Fail)
        ]
    );
    let scenes = by_scene(&judged);
    assert_eq!(scenes.len(), 1, "{scenes:?}");
    assert_eq!(
        scenes[0].disagreements(),
        [("povray", "fake"), ("oracle", "fake")]
    );
    let dir = std::env::temp_dir().join(format!("registry-fail-{}", std::process::id()));
    let m = judged[2].failure_message_to(&dir);
    assert!(m.starts_with("fake/prim_sphere_identity: FAIL\n"), "{m}");
    assert!(m.contains("fake metric") && m.contains("fake class"), "{m}");
    assert!(m.contains("#prim_sphere_identity@fake"), "{m}");
    assert!(dir.join("fakefig.png").is_file() && dir.join("difference.png").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test03_waivers_take_its_checks() {
    let r = registry();
    let text = |check: &str| {
        format!("[[waiver]]\nscene = \"fake/{SCENE}\"\ncheck = \"{check}\"\nreason = \"r\"\ndate = \"2026-11-27\"\n")
    };
    let path = Path::new("waivers.toml");
    let w = Waivers::parse_with(&text("grey"), path, &r).unwrap();
    let e = Waivers::parse_with(&text("pixels"), path, &r)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a check of fake (one of: grey)"), "{e}");
    let e = Waivers::parse(&text("grey"), path).unwrap_err().to_string();
    assert!(e.contains("unknown reference `fake`"), "{e}");
    // Its failure, waived, is WAIVED; POV-Ray's pass stays a pass.
    let judged = check_all(&r, SCENE, &manifest(), &w).unwrap();
    assert_eq!(judged[2].verdict, Verdict::Waived);
    assert_eq!(judged[0].verdict, Verdict::Pass);
    let (_, e) = r.select("fake::prim_sphere_identity").unwrap().remove(0);
    let again = judge(FAKE.compare(&e, &manifest()).unwrap(), &w);
    assert_eq!(again.verdict, Verdict::Waived);
}

#[test]
fn test04_the_report_shows_it() {
    let r = registry();
    let judged = check_all(&r, SCENE, &manifest(), &Waivers::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("registry-report-{}", std::process::id()));
    conformance::report::write(&dir, &judged, &r).unwrap();
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    for want in [
        "<tr><td>fake</td>",
        "FAKE-LEGEND",
        "FAKE-PLOT",
        "<tr id=\"prim_sphere_identity@fake\"",
        "<tr id=\"prim_sphere_identity\"",
        "prim_sphere_identity@fake/fakefig.png",
        "povray and fake disagree",
        // The oracle's three-way vote on the scene, in its agreement cell.
        "three-way: ours~POV-Ray agree, oracle~POV-Ray agree, ours~oracle agree",
    ] {
        assert!(html.contains(want), "the report lacks {want:?}");
    }
    assert!(dir.join("prim_sphere_identity@fake/fakefig.png").is_file());
    let results = std::fs::read_to_string(dir.join("results.json")).unwrap();
    assert!(
        results.contains("\"reference\": \"fake\"") && results.contains("a grey card (Fake)"),
        "{results}"
    );
    let table = conformance::report::table(&judged);
    assert!(
        table.contains("fake ") && table.contains("fake metric"),
        "{table}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
