//! An instance is only a placement: nested transparent objects inside one instanced
//! definition render like the same shapes written as groups. (The interior list once
//! keyed surfaces by object id, which every shape inside an instance shares, so a ray
//! inside the glass block took the water drop for the block it was in; 121 pixels failed.)
//! Each scene also passes against its own POV-Ray reference in the catalog gate.

use conformance::catalog::{load, scenes};
use conformance::povray::harness::{compare_render, render_for_conformance};
use renderer::render::Options;
use renderer::scene::Scene;

fn render(name: &str) -> (Scene, renderer::render::Image) {
    let e = scenes("povray", name)
        .unwrap()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("catalog scene {name} is missing"));
    let scene = load(&e).unwrap().0;
    let img = render_for_conformance(&scene);
    (scene, img)
}

#[test]
fn nested_glass_renders_alike_as_groups_and_as_instances() {
    let (_, group) = render("shade_nested_glass_group");
    let (scene, instance) = render("shade_nested_glass_instance");
    let w = group.width as usize;
    let c = compare_render(&scene, &Options::default(), &instance, &group.rgb);
    let worst = c
        .class
        .iter()
        .enumerate()
        .filter(|(_, &k)| k != 0)
        .take(10)
        .map(|(k, _)| format!("({}, {})", k % w, k / w))
        .collect::<Vec<_>>();
    assert!(
        c.failing == 0 && c.silhouette <= 2,
        "the instanced definition renders unlike the groups: {} failing, {} edge pixels \
         (max abs {:.2e}), first at {}; see renderer/src/shading.rs (Interiors) and \
         Hit::surface in renderer/src/hit.rs",
        c.failing,
        c.silhouette,
        c.max_abs,
        worst.join(" ")
    );
}
