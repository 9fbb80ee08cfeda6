"""Physical scenes for the Mitsuba comparison of scripts/bench_peers.py that are in no
catalog: the estimator was never tuned on them. Each is our scene format (TOML); `write`
puts one into a folder at a given size, with the mesh it needs.

- bench_sphere_glass: two coloured sphere lights, a glass sphere and a glass box on a
  floor before a back wall (`path`, caustics through glass).
- bench_interreflection: a white room lit only around a corner: the light shines into an
  alcove, and the camera sees the room by what its walls pass on (`path`, depth 8).
- bench_mixed_lights: a point, a rectangle, a directional and an environment light on
  spheres, a box and a cylinder (`direct`).
- bench_mesh: three instances of a bumpy 20,480-triangle rock and a mirror sphere under a
  rectangle light (`path`).
"""

import math
import os

HEAD = """[camera.look_at]
from = {eye}
at = {at}
up = [0, 1, 0]
fov = {fov}

[render]
width = {size}
height = {size}
integrator = "{integrator}"
max_depth = {depth}
"""

MATERIALS = """
[materials.white]
model = "diffuse"
color = [0.75, 0.75, 0.75]

[materials.red]
model = "diffuse"
color = [0.7, 0.15, 0.1]

[materials.green]
model = "diffuse"
color = [0.15, 0.5, 0.12]

[materials.blue]
model = "diffuse"
color = [0.15, 0.25, 0.7]

[materials.glass]
model = "dielectric"
ior = 1.5

[materials.mirror]
model = "conductor"
color = [0.9, 0.9, 0.9]
"""

SCENES = {
    "bench_sphere_glass": (
        dict(eye="[0, 2.2, -6]", at="[0, 0.4, 0]", fov=42, integrator="path", depth=8),
        """
[materials.warm]
model = "diffuse"
color = [0, 0, 0]
radiance = [9, 6, 3]

[materials.cool]
model = "diffuse"
color = [0, 0, 0]
radiance = [2, 4, 9]

[[objects]]
type = "rectangle"
material = "white"
transform = [{ scale = 8 }, { translate = [0, -1, 0] }]

[[objects]]
type = "rectangle"
material = "red"
transform = [{ scale = 8 }, { rotate = { axis = [1, 0, 0], degrees = -90 } }, { translate = [0, 3, 3] }]

[[objects]]
type = "sphere"
material = "warm"
transform = [{ scale = 0.3 }, { translate = [-1.8, 1.6, 0.5] }]

[[objects]]
type = "sphere"
material = "cool"
transform = [{ scale = 0.25 }, { translate = [1.9, 1.2, -0.4] }]

[[objects]]
type = "sphere"
material = "glass"
transform = [{ scale = 0.8 }, { translate = [-0.5, -0.2, 0.2] }]

[[objects]]
type = "box"
material = "glass"
transform = [{ scale = 0.45 }, { rotate = { axis = [0, 1, 0], degrees = 35 } }, { translate = [1.1, -0.55, -0.3] }]

[[objects]]
type = "sphere"
material = "blue"
transform = [{ scale = 0.35 }, { translate = [0.4, -0.65, 1.4] }]
""",
    ),
    "bench_interreflection": (
        dict(eye="[-0.6, 1.0, -2.9]", at="[0.3, 0.9, 0.5]", fov=60, integrator="path", depth=8),
        """
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [30, 28, 24]

# A room 4 wide, 2 high and 6 deep, open nowhere; the alcove at x > 1 behind the wall
# x = 1, z in 0..3 holds the light, which faces away from the camera.
[[objects]]
type = "box"
material = "white"
transform = [{ scale = [2, 0.02, 3] }, { translate = [0, -0.02, 0] }]

[[objects]]
type = "box"
material = "white"
transform = [{ scale = [2, 0.02, 3] }, { translate = [0, 2.02, 0] }]

[[objects]]
type = "box"
material = "green"
transform = [{ scale = [0.02, 1, 3] }, { translate = [-2.02, 1, 0] }]

[[objects]]
type = "box"
material = "white"
transform = [{ scale = [0.02, 1, 3] }, { translate = [2.02, 1, 0] }]

[[objects]]
type = "box"
material = "white"
transform = [{ scale = [2, 1, 0.02] }, { translate = [0, 1, 3.02] }]

[[objects]]
type = "box"
material = "white"
transform = [{ scale = [2, 1, 0.02] }, { translate = [0, 1, -3.02] }]

# The wall that hides the alcove.
[[objects]]
type = "box"
material = "white"
transform = [{ scale = [0.05, 1, 1.5] }, { translate = [1, 1, 1.5] }]

[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.3 }, { rotate = { axis = [0, 0, 1], degrees = -90 } }, { translate = [1.98, 1.2, 1.8] }]

[[objects]]
type = "box"
material = "red"
transform = [{ scale = [0.3, 0.5, 0.3] }, { rotate = { axis = [0, 1, 0], degrees = 25 } }, { translate = [-0.8, 0.5, 1.2] }]

[[objects]]
type = "sphere"
material = "white"
transform = [{ scale = 0.35 }, { translate = [0.2, 0.35, 0.4] }]
""",
    ),
    "bench_mixed_lights": (
        dict(eye="[0, 1.8, -5.5]", at="[0, 0.2, 0]", fov=45, integrator="direct", depth=2),
        """
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [6, 6, 5]

[[lights]]
position = [-2.5, 3, -2]
color = [10, 8, 6]

[[lights]]
type = "directional"
direction = [0.5, -1, 0.3]
color = [1.2, 1.3, 1.5]

[[lights]]
type = "environment"
color = [0.1, 0.12, 0.16]

[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.6 }, { rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [1.2, 2.5, 0.5] }]

[[objects]]
type = "rectangle"
material = "white"
transform = [{ scale = 7 }, { translate = [0, -1, 0] }]

[[objects]]
type = "sphere"
material = "red"
transform = [{ scale = 0.7 }, { translate = [-1.1, -0.3, 0.3] }]

[[objects]]
type = "box"
material = "blue"
transform = [{ scale = 0.45 }, { rotate = { axis = [0, 1, 0], degrees = 20 } }, { translate = [0.9, -0.55, -0.2] }]

[[objects]]
type = "cylinder"
material = "green"
transform = [{ scale = [0.3, 0.9, 0.3] }, { translate = [0.1, -0.1, 1.4] }]

[[objects]]
type = "sphere"
material = "white"
transform = [{ scale = 0.25 }, { translate = [1.6, -0.75, -1.2] }]
""",
    ),
    "bench_mesh": (
        dict(eye="[0, 2.0, -5.5]", at="[0, 0.1, 0]", fov=45, integrator="path", depth=6),
        """
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [12, 11, 10]

[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.7 }, { rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 3, 0] }]

[[objects]]
type = "rectangle"
material = "white"
transform = [{ scale = 7 }, { translate = [0, -1, 0] }]

[defs.rock]
type = "mesh"
file = "rock.obj"

[[objects]]
type = "instance"
of = "rock"
material = "red"
transform = [{ scale = 0.7 }, { translate = [-1.2, -0.35, 0.2] }]

[[objects]]
type = "instance"
of = "rock"
material = "white"
transform = [{ scale = [0.5, 0.8, 0.5] }, { rotate = { axis = [0, 1, 0], degrees = 40 } }, { translate = [0.3, -0.2, 0.9] }]

[[objects]]
type = "instance"
of = "rock"
material = "blue"
transform = [{ scale = 0.45 }, { rotate = { axis = [1, 0, 0], degrees = 70 } }, { translate = [1.3, -0.55, -0.5] }]

[[objects]]
type = "sphere"
material = "mirror"
transform = [{ scale = 0.4 }, { translate = [-0.1, -0.6, -0.9] }]
""",
    ),
}

NAMES = list(SCENES)


def rock_obj(levels=5):
    """A bumpy icosphere (20·4^levels triangles), deterministic, as OBJ text."""
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid = {}

        def split(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[key] = len(v) - 1
            return mid[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = split(a, b), split(b, c), split(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf

    def bump(p):
        x, y, z = p
        return 1 + 0.08 * math.sin(7 * x + 1) * math.sin(6 * y + 2) * math.sin(5 * z + 3) + 0.03 * math.sin(23 * x * y)

    lines = ["# bench_mesh's rock: a bumpy icosphere (scripts/bench_scenes.py)"]
    lines += [f"v {x * bump((x, y, z)):.6f} {y * bump((x, y, z)):.6f} {z * bump((x, y, z)):.6f}" for x, y, z in v]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f]
    return "\n".join(lines) + "\n"


def text(name, size):
    """Scene NAME as TOML text at size x size pixels."""
    head, body = SCENES[name]
    return HEAD.format(size=size, **head) + MATERIALS + body


def write(name, folder, size):
    """Writes scene NAME (and the mesh it names) into `folder`; returns the scene's path."""
    os.makedirs(folder, exist_ok=True)
    if name == "bench_mesh" and not os.path.exists(os.path.join(folder, "rock.obj")):
        open(os.path.join(folder, "rock.obj"), "w").write(rock_obj())
    path = os.path.join(folder, name + ".toml")
    open(path, "w").write(text(name, size))
    return path
