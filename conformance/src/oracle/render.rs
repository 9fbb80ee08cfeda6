//! The oracle for one scene: its image at pixel centres, and a sample at any continuous
//! pixel position (what the comparison re-traces).

use super::camera::Camera;
use super::shade::Ticket;
use super::world::World;
use crate::povray::compare::Sample;
use renderer::scene::Scene;

/// The oracle for one scene.
pub struct Oracle {
    world: World,
    camera: Camera,
    width: usize,
    height: usize,
}

impl Oracle {
    /// The oracle for `scene`, or the reason it declines the scene.
    pub fn new(scene: &Scene) -> Result<Oracle, String> {
        Ok(Oracle {
            world: World::new(scene)?,
            camera: Camera::new(&scene.camera.model),
            width: scene.settings.width as usize,
            height: scene.settings.height as usize,
        })
    }

    /// The camera sample at a continuous pixel position (x right, y down, pixel (i, j)'s
    /// centre at (i + ½, j + ½)), as the comparison re-traces it.
    pub fn sample(&self, x: f64, y: f64) -> Sample {
        let ray = self.camera.ray(x, y);
        let start = Ticket {
            level: 0,
            weight: 1.0,
            interiors: Vec::new(),
        };
        let (c, hit) = self.world.trace(&ray, &start, false, 0.0);
        let secondary = hit.is_some_and(|h| {
            let m = &self.world.materials[self.world.objects[h.object].material];
            m.reflection > 0.0 || m.filter > 0.0 || m.transmit > 0.0
        });
        Sample {
            rgb: c.to_array().map(|v| v as f32),
            object: hit.map_or(0, |h| h.object as u32 + 1),
            secondary,
        }
    }

    /// The image at pixel centres: RGB, row-major, top row first.
    pub fn render(&self) -> Vec<f32> {
        let mut rgb = Vec::with_capacity(self.width * self.height * 3);
        for j in 0..self.height {
            for i in 0..self.width {
                rgb.extend_from_slice(&self.sample(i as f64 + 0.5, j as f64 + 0.5).rgb);
            }
        }
        rgb
    }

    /// Width and height.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A 3×3 image of one unit sphere seen head-on from (0, 0, −5), lit from the eye,
    /// with `material` (TOML keys) and `render` (extra TOML keys): the oracle's value at
    /// the centre pixel, whose ray hits the sphere at (0, 0, −1) with N·L = 1.
    fn centre(material: &str, render: &str) -> [f32; 3] {
        let text = format!(
            r#"
[camera.look_at]
from = [0, 0, -5]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 20

[render]
width = 3
height = 3
background = [0.2, 0.4, 0.8]
{render}

[[lights]]
position = [0, 0, -5]
color = [1, 1, 1]

[materials.m]
color = [0.5, 0.25, 1.0]
{material}

[[objects]]
type = "sphere"
material = "m"
"#
        );
        let scene = Scene::from_str(&text, Path::new("oracle-test.toml"), Path::new("."))
            .expect("the test scene loads");
        Oracle::new(&scene)
            .expect("the oracle covers it")
            .sample(1.5, 1.5)
            .rgb
    }

    fn close(got: [f32; 3], want: [f64; 3]) {
        for c in 0..3 {
            assert!(
                (got[c] as f64 - want[c]).abs() < 1e-6,
                "got {got:?}, want {want:?}"
            );
        }
    }

    #[test]
    fn test01_ambient_and_diffuse_head_on() {
        // 0.1·P (ambient, ambient_light 1) + 0.6·(N·L = 1)·P.
        close(centre("", ""), [0.35, 0.175, 0.7]);
        // Brilliance leaves N·L = 1 alone; diffuse scales it.
        close(
            centre("diffuse = 0.2\nbrilliance = 3", ""),
            [0.15, 0.075, 0.3],
        );
    }

    #[test]
    fn test02_phong_and_specular_peak_at_the_mirror_direction() {
        // R = D − 2(D·N)N = −D points back at the light: c = 1, so + phong · 1.
        close(centre("phong = 0.5", ""), [0.85, 0.675, 1.2]);
        // H = ½(−D + L) = −D: c = 1, so + specular · 1.
        close(
            centre("specular = 0.25\nroughness = 0.05", ""),
            [0.6, 0.425, 0.95],
        );
    }

    #[test]
    fn test03_a_straight_through_surface_uses_no_trace_level() {
        // A clear sphere of ior 1 with max_depth 2: the camera ray uses the first level,
        // passes both surfaces without using another, and returns the background
        // filtered twice by P·filter = P.
        let clear = "ambient = 0\ndiffuse = 0\nfilter = 1";
        close(
            centre(&format!("{clear}\nior = 1"), "max_depth = 2"),
            [0.05, 0.025, 0.8],
        );
        // With ior 1.5 the ray out of the back needs a third level: black.
        close(
            centre(&format!("{clear}\nior = 1.5"), "max_depth = 2"),
            [0.0, 0.0, 0.0],
        );
    }

    #[test]
    fn test04_it_declines_what_it_does_not_model_and_says_why() {
        let dir = crate::catalog::repo_root().join("conformance/scenes/mitsuba");
        let path = dir.join("mi_diffuse_point.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let scene = Scene::from_str(&text, &path, &dir).unwrap();
        let why = Oracle::new(&scene)
            .err()
            .expect("a physically based scene is declined");
        assert!(why.contains("physically based integrator"), "{why}");
    }
}
