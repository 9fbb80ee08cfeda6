#!/usr/bin/env python3
"""Writes the POV-Ray conformance catalog: conformance/scenes/povray/*.toml.

Each scene checks one feature. The files are data: they are committed, and this script
only saves typing them. No two surfaces in a scene are coplanar (a slab resting exactly on
the floor makes the first hit a tie, which two renderers may break differently), and no
pixel-centre ray is exactly parallel to an infinite plane (whether it hits then depends on
the sign of a rounding error). Run it from anywhere:

    python3 scripts/gen_catalog.py

The catalog has camera scenes (cam_*), every primitive under seven transforms
(prim_<shape>_<transform>), a hierarchy and an instancing scene (hier_*), shading scenes
(shade_*), and scenes with small features for the localized sensitivity tests (loc_*).
Resolution is small (96x72) so that the whole catalog renders in seconds.
"""
import math
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
OUT = os.path.join(ROOT, "conformance", "scenes", "povray")

W, H = 96, 72

LOOK = """[camera.look_at]
from = [0.6, 1.8, -5.5]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 42
"""


def render(w=W, h=H, extra=""):
    return f"""
[render]
width = {w}
height = {h}
background = [0.1, 0.12, 0.2]
{extra}"""


LIGHT = """
[[lights]]
position = [-5, 7, -6]
color = [1, 1, 1]
"""

MATERIALS = """
[materials.matte]
color = [0.85, 0.55, 0.3]
phong = 0.4
phong_size = 30

[materials.floor]
color = [0.7, 0.72, 0.75]
"""


FLOOR = """
[[objects]]
type = "plane"
material = "floor"
transform = [{ translate = [0, -1, 0] }]
"""


def write(name, text):
    path = os.path.join(OUT, name + ".toml")
    with open(path, "w") as f:
        f.write(text.lstrip())


def tf(ops):
    return "transform = [" + ", ".join(ops) + "]" if ops else ""


# The seven transforms every primitive is rendered under.
TRANSFORMS = {
    "identity": [],
    "translate": ["{ translate = [0.4, -0.3, 0.5] }"],
    "rotate": ["{ rotate = { axis = [1, 1, 0.3], degrees = 35 } }"],
    "scale": ["{ scale = 0.7 }"],
    "nonuniform": ["{ scale = [1.2, 0.6, 0.8] }", "{ rotate = { axis = [0, 1, 0], degrees = 20 } }"],
    "shear": ["{ shear = { xy = 0.4, zx = 0.3 } }", "{ rotate = { axis = [0, 1, 0], degrees = 15 } }"],
    "mirror": ["{ scale = [-1, 1, 1] }", "{ rotate = { axis = [1, 0.5, 0], degrees = 30 } }"],
}

# Each primitive with the node fields it needs and a base placement that shows it well.
PRIMITIVES = {
    "sphere": ('type = "sphere"', []),
    "box": ('type = "box"', ["{ scale = 0.8 }", "{ rotate = { axis = [0, 1, 0], degrees = 25 } }"]),
    "cylinder": ('type = "cylinder"', ["{ scale = [0.7, 1, 0.7] }", "{ rotate = { axis = [1, 0, 0], degrees = -25 } }"]),
    "cylopen": ('type = "cylinder"\ncapped = false', ["{ scale = [0.7, 1, 0.7] }", "{ rotate = { axis = [1, 0, 0], degrees = -35 } }"]),
    "cone": ('type = "cone"', ["{ rotate = { axis = [1, 0, 0], degrees = -20 } }"]),
    "disk": ('type = "disk"', ["{ rotate = { axis = [1, 0, 0], degrees = -65 } }"]),
    "rectangle": ('type = "rectangle"', ["{ rotate = { axis = [1, 0, 0], degrees = -60 } }", "{ rotate = { axis = [0, 1, 0], degrees = 20 } }"]),
    "triangle": ('type = "triangle"\nvertices = [[-1.2, -1, 0.2], [0.1, 1.2, -0.3], [1.1, -0.8, 0.1]]', []),
    "mesh": ('type = "mesh"\nfile = "../meshes/icosphere.obj"', []),
    "plane": ('type = "plane"', ["{ rotate = { axis = [1, 0, 0], degrees = -10 } }", "{ translate = [0, -0.8, 0] }"]),
}


def primitives():
    for prim, (fields, base) in PRIMITIVES.items():
        for tname, ops in TRANSFORMS.items():
            node = f"""
# {prim} under the {tname} transform (applied after the base placement).
[[objects]]
{fields}
material = "matte"
{tf(base + ops)}
"""
            write(f"prim_{prim}_{tname}", LOOK + render() + LIGHT + MATERIALS + node)


def cameras():
    sphere_row = """
[[objects]]
type = "plane"
material = "floor"
transform = [{ translate = [0, -1, 0] }]

[[objects]]
type = "sphere"
material = "matte"

[[objects]]
type = "box"
material = "matte"
transform = [{ scale = 0.5 }, { rotate = { axis = [0, 1, 0], degrees = 30 } }, { translate = [2, -0.5, 1] }]

[[objects]]
type = "cone"
material = "matte"
transform = [{ scale = 0.6 }, { translate = [-2, -0.4, 0.5] }]
"""
    view = lambda vrp, vpn, vup, e, win: f"""[camera.view]
vrp = {vrp}
vpn = {vpn}
vup = {vup}
e = {e}
window = {{ left = {win[0]}, right = {win[1]}, bottom = {win[2]}, top = {win[3]} }}
"""
    scenes = {
        # VRP off the origin, an oblique VPN and a rolled VUP.
        "cam_oblique_roll": view("[1.5, 2.5, -3.0]", "[-0.3, -0.45, 1]", "[0.4, 1, 0.1]", 2.0, (-1.2, 1.2, -0.9, 0.9)),
        # Small E: the eye is close to a small window (wide view).
        "cam_small_e": view("[0, 0.3, -4]", "[0, -0.1, 1]", "[0, 1, 0]", 0.25, (-0.3, 0.3, -0.225, 0.225)),
        # Large E: a distant eye and a wide window (narrow view, little perspective).
        "cam_large_e": view("[0, 0.3, -4]", "[0, -0.1, 1]", "[0, 1, 0]", 40.0, (-3.2, 3.2, -2.4, 2.4)),
        # An asymmetric window: the view is off-centre.
        "cam_asymmetric": view("[0, 0.5, -4]", "[0, 0, 1]", "[0, 1, 0]", 2.5, (-2.4, 0.6, -1.5, 0.75)),
        # A non-square pixel array: 320x120 pixels on a 4:3 window (pixels 2:1 tall).
        # (vpn is tilted by 0.13, not 0.1: with 0.1 the rays of pixel row 47 are exactly
        # parallel to the floor, and whether they hit it depends on rounding.)
        "cam_nonsquare": view("[0, 0.5, -4]", "[0, -0.13, 1]", "[0, 1, 0]", 2.5, (-1.6, 1.6, -1.2, 1.2)),
    }
    for name, cam in scenes.items():
        res = render(320, 120) if name == "cam_nonsquare" else render()
        write(name, cam + res + LIGHT + MATERIALS + sphere_row)
    look = lambda fov, axis="horizontal", frm="[0.6, 1.8, -5.5]": f"""[camera.look_at]
from = {frm}
at = [0, 0, 0]
up = [0, 1, 0]
fov = {fov}
fov_axis = "{axis}"
"""
    write("cam_wide_fov", look(150, frm="[0.3, 0.6, -2.2]") + render() + LIGHT + MATERIALS + sphere_row)
    write("cam_narrow_fov", look(0.8, frm="[20, 40, -300]") + render() + LIGHT + MATERIALS + sphere_row)
    write("cam_vertical_fov", look(35, "vertical") + render(64, 96) + LIGHT + MATERIALS + sphere_row)
    pov = """[camera.povray]
location = [0.5, 1.5, -5]
direction = [0.3, -0.2, 2.2]
right = [1.6, 0, 0]
up = [0, 1.2, 0]
"""
    write("cam_povray_form", pov + render() + LIGHT + MATERIALS + sphere_row)


def hierarchy():
    h3 = """
# A three-level hierarchy: table > legs > leg, transforms composed at each level.
[[objects]]
type = "plane"
material = "floor"
transform = [{ translate = [0, -1, 0] }]

[[objects]]
type = "group"
transform = [{ rotate = { axis = [0, 1, 0], degrees = 25 } }, { translate = [0, -0.2, 0] }]
children = [
  { type = "box", material = "matte", transform = [{ scale = [1.6, 0.08, 1.0] }, { translate = [0, 0.6, 0] }] },
  { type = "group", transform = [{ scale = [1, 1.1, 1] }], children = [
      { type = "cylinder", transform = [{ scale = [0.08, 0.45, 0.08] }, { translate = [-1.4, -0.05, -0.8] }] },
      { type = "cylinder", transform = [{ scale = [0.08, 0.45, 0.08] }, { translate = [1.4, -0.05, -0.8] }] },
      { type = "group", transform = [{ translate = [0, -0.05, 0.8] }], children = [
          { type = "cylinder", transform = [{ scale = [0.08, 0.45, 0.08] }, { translate = [-1.4, 0, 0] }] },
          { type = "cylinder", transform = [{ scale = [0.08, 0.45, 0.08] }, { translate = [1.4, 0, 0] }] },
      ] },
  ] },
  { type = "sphere", transform = [{ scale = 0.3 }, { translate = [0.5, 0.98, 0] }] },
]
"""
    write("hier_three_levels", LOOK + render() + LIGHT + MATERIALS + h3)
    inst = ["""
# One definition (a sphere on a sheared box) instanced 60 times: stored once.
[defs.post]
type = "group"
children = [
  { type = "box", transform = [{ scale = [0.12, 0.3, 0.12] }, { shear = { xy = 0.3 } }] },
  { type = "sphere", transform = [{ scale = 0.16 }, { translate = [0.09, 0.42, 0] }] },
]

[[objects]]
type = "plane"
material = "floor"
transform = [{ translate = [0, -1, 0] }]
"""]
    for k in range(60):
        x = -2.5 + (k % 10) * 0.55
        z = -1.0 + (k // 10) * 0.7
        ang = (k * 37) % 360
        inst.append(f"""
[[objects]]
type = "instance"
of = "post"
material = "matte"
transform = [{{ rotate = {{ axis = [0, 1, 0], degrees = {ang} }} }}, {{ translate = [{x:.2f}, -0.65, {z:.2f}] }}]
""")
    write("hier_instanced", LOOK + render() + LIGHT + MATERIALS + "".join(inst))


def shading():
    floor = FLOOR
    def one(name, finish, comment, lights=LIGHT, objects=None, extra_render=""):
        mat = f"\n# {comment}\n[materials.test]\n{finish}\n"
        objs = objects or """
[[objects]]
type = "sphere"
material = "test"
"""
        write(name, LOOK + render(extra=extra_render) + lights + MATERIALS + mat + floor + objs)

    # Each finish term alone (the others zeroed).
    base = "color = [0.9, 0.5, 0.3]\nambient = 0\ndiffuse = 0\n"
    one("shade_ambient", "color = [0.9, 0.5, 0.3]\nambient = 0.6\ndiffuse = 0", "Ambient only.",
        extra_render="ambient_light = [0.8, 0.9, 1.0]")
    one("shade_diffuse", "color = [0.9, 0.5, 0.3]\nambient = 0\ndiffuse = 0.8", "Diffuse only (brilliance 1).")
    one("shade_brilliance", "color = [0.9, 0.5, 0.3]\nambient = 0\ndiffuse = 0.8\nbrilliance = 4", "Diffuse with brilliance 4.")
    one("shade_phong", base + "phong = 0.9\nphong_size = 25", "Phong highlight only.")
    one("shade_phong_size", base + "phong = 0.9\nphong_size = 200", "A tight phong highlight (phong_size >= 60).")
    one("shade_specular", base + "specular = 0.9\nroughness = 0.02", "Blinn specular only.")
    one("shade_emission", "color = [0.9, 0.5, 0.3]\nambient = 0\ndiffuse = 0\nemission = 0.7", "Emission only.")
    two = """
[[lights]]
position = [-5, 7, -6]
color = [0.7, 0.6, 0.5]

[[lights]]
position = [4, 5, -3]
color = [0.3, 0.4, 0.6]
"""
    one("shade_shadows_two_lights", "color = [0.9, 0.5, 0.3]\nphong = 0.3", "Hard shadows from two lights.", lights=two,
        objects="""
[[objects]]
type = "sphere"
material = "test"
transform = [{ scale = 0.7 }, { translate = [0, -0.2, 0] }]

[[objects]]
type = "box"
material = "test"
transform = [{ scale = [0.3, 0.6, 0.3] }, { translate = [1.5, -0.4, 0.8] }]
""")
    fade = """
[[lights]]
position = [-2, 3, -2]
color = [2, 2, 2]
fade_distance = 2
fade_power = 2
"""
    one("shade_light_fade", "color = [0.9, 0.5, 0.3]", "A light with fade_distance and fade_power.", lights=fade)
    one("shade_reflection_chain", "color = [0.2, 0.2, 0.25]\nambient = 0.02\ndiffuse = 0.2\nreflection = 0.8",
        "Two facing mirrors and a sphere between them: a chain of reflections cut by max_depth.",
        objects="""
[[objects]]
type = "box"
material = "test"
transform = [{ scale = [0.05, 1.2, 2] }, { translate = [-1.8, 0, 0.5] }]

[[objects]]
type = "box"
material = "test"
transform = [{ scale = [0.05, 1.2, 2] }, { translate = [1.8, 0, 0.5] }]

[[objects]]
type = "sphere"
material = "matte"
transform = [{ scale = 0.5 }]
""")
    glass = "color = [0.95, 0.97, 1.0]\nambient = 0\ndiffuse = 0.05\nfilter = 0.9\nphong = 0.5\nior = 1.5"
    checker = """
[[objects]]
type = "box"
material = "matte"
transform = [{ scale = [0.3, 0.3, 0.3] }, { translate = [-0.9, -0.7, 2] }]

[[objects]]
type = "cylinder"
material = "floor"
transform = [{ scale = [0.2, 1.2, 0.2] }, { translate = [0.7, 0, 2.5] }]
"""
    one("shade_refract_sphere", glass, "A glass sphere (ior 1.5) in front of other objects.",
        objects="""
[[objects]]
type = "sphere"
material = "test"
transform = [{ scale = 0.9 }]
""" + checker)
    one("shade_refract_slab", glass, "A tilted glass slab: the view shifts through it.",
        objects="""
[[objects]]
type = "box"
material = "test"
transform = [{ scale = [1.2, 0.85, 0.15] }, { rotate = { axis = [0, 1, 0], degrees = 35 } }]
""" + checker)
    one("shade_total_internal", "color = [0.95, 0.97, 1.0]\nambient = 0\ndiffuse = 0\nfilter = 0.95\nior = 2.4",
        "A high-ior prism-like block seen edge-on: rays inside meet its faces past the critical angle.",
        objects="""
[[objects]]
type = "box"
material = "test"
transform = [{ scale = [1.4, 0.5, 0.5] }, { rotate = { axis = [0, 0, 1], degrees = 45 } }, { rotate = { axis = [0, 1, 0], degrees = 30 } }]
""" + checker)
    nested_glass()
    one("shade_transmit", "color = [0.3, 0.8, 0.4]\ntransmit = 0.5\nfilter = 0.2\nphong = 0.5",
        "Filter and transmit with ior 1: light passes straight through and tints shadows.",
        objects="""
[[objects]]
type = "sphere"
material = "test"
transform = [{ scale = 0.8 }]
""" + checker)


# A glass block (ior 1.5) holding a water drop (ior 1.33), placed twice, once mirrored.
# Inside the block a ray meets the drop: it must refract by 1.5/1.33 going in and
# 1.33/1.5 coming out. The same two shapes are written once as groups and once as a
# definition with two instances; both must render alike (an instance is only a placement).
NESTED_MATERIALS = """
[materials.glass]
color = [0.95, 0.97, 1.0]
ambient = 0
diffuse = 0.05
filter = 0.9
phong = 0.5
ior = 1.5

[materials.water]
color = [0.8, 0.9, 1.0]
ambient = 0
diffuse = 0.05
filter = 0.85
ior = 1.33
"""
NESTED_CHILDREN = """children = [
  { type = "box", material = "glass", transform = [{ scale = [0.55, 0.7, 0.45] }] },
  { type = "sphere", material = "water", transform = [{ scale = 0.32 }, { translate = [0.08, 0.12, -0.05] }] },
]"""
NESTED_PLACEMENTS = [
    "[{ rotate = { axis = [0, 1, 0], degrees = 25 } }, { translate = [-0.85, -0.2, 0] }]",
    "[{ scale = [-1, 1, 1] }, { rotate = { axis = [1, 0.2, 0], degrees = 12 } }, { translate = [0.9, -0.15, 0.3] }]",
]
NESTED_BACKDROP = FLOOR + """
[[objects]]
type = "box"
material = "matte"
transform = [{ scale = [0.25, 0.25, 0.25] }, { translate = [-0.5, -0.6, 2.2] }]

[[objects]]
type = "cylinder"
material = "floor"
transform = [{ scale = [0.15, 1.3, 0.15] }, { translate = [0.45, 0, 2.6] }]

[[objects]]
type = "sphere"
material = "matte"
transform = [{ scale = 0.3 }, { translate = [1.6, -0.4, 2.0] }]
"""


def nested_glass():
    head = LOOK + render() + LIGHT + MATERIALS + NESTED_MATERIALS + NESTED_BACKDROP
    groups = "".join(
        f'\n[[objects]]\ntype = "group"\n{NESTED_CHILDREN}\ntransform = {p}\n' for p in NESTED_PLACEMENTS)
    write("shade_nested_glass_group",
          "# Nested transparent objects (a drop inside a block), as two groups.\n" + head + groups)
    defs = f'\n[defs.block]\ntype = "group"\n{NESTED_CHILDREN}\n'
    insts = "".join(
        f'\n[[objects]]\ntype = "instance"\nof = "block"\ntransform = {p}\n' for p in NESTED_PLACEMENTS)
    write("shade_nested_glass_instance",
          "# Nested transparent objects (a drop inside a block), as one definition instanced twice.\n"
          + head + defs + insts)


def localized():
    """Small features, each of which a localized fault changes in a few pixels only
    (tests/localized.rs)."""
    pool = """
# A low light with fade: it lights a pool on the floor and little else.
[[lights]]
position = [1.25, -0.6, -0.6]
color = [0.9, 0.8, 0.5]
fade_distance = 0.4
fade_power = 2
"""
    mats = """
# A small shiny sphere with its own finish.
[materials.shiny]
color = [0.3, 0.45, 0.9]
phong = 0.8
phong_size = 40

# A glass sphere (ior 1.5) with its own interior.
[materials.glass]
color = [0.95, 0.97, 1.0]
ambient = 0
diffuse = 0.05
filter = 0.9
ior = 1.5
"""
    objs = FLOOR + """
[[objects]]
type = "sphere"
material = "shiny"
transform = [{ scale = 0.2 }, { translate = [-1.1, -0.8, -1.0] }]

[[objects]]
type = "sphere"
material = "glass"
transform = [{ scale = 0.22 }, { translate = [0.1, -0.7, -0.2] }]

[[objects]]
type = "box"
material = "matte"
transform = [{ scale = 0.4 }, { rotate = { axis = [0, 1, 0], degrees = 30 } }, { translate = [0.5, -0.6, 1.4] }]

[[objects]]
type = "cylinder"
material = "floor"
transform = [{ scale = [0.15, 0.8, 0.15] }, { translate = [-0.5, -0.2, 1.6] }]
"""
    write("loc_small_objects", LOOK + render() + LIGHT + pool + MATERIALS + mats + objs)
    # A thin disk 0.005 above the floor. The light is 42 degrees high, so the floor's
    # shadow rays meet the disk 0.0075 from their origin: POV-Ray's shadow tolerance of
    # 1e-3 keeps that shadow, and a tolerance ten times larger would lose it. The camera
    # looks closely at the rim on the shadow's side, where a sliver of the shadow shows.
    near = """[camera.look_at]
from = [0.6, 1.8, -5.5]
at = [0.4, -1, -0.5]
up = [0, 1, 0]
fov = 4
"""
    disk = FLOOR + """
[[objects]]
type = "disk"
material = "matte"
transform = [{ scale = 0.6 }, { translate = [0, -0.995, 0] }]
"""
    write("loc_contact_shadow", near + render() + LIGHT + MATERIALS + disk)


def mesh():
    """An icosphere (subdivided twice) with vertex normals, for the mesh primitive."""
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(2):
        cache = {}
        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(verts[a][k] + verts[b][k]) / 2 for k in range(3)]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[key] = len(verts) - 1
            return cache[key]
        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    os.makedirs(os.path.join(ROOT, "conformance", "scenes", "meshes"), exist_ok=True)
    with open(os.path.join(ROOT, "conformance", "scenes", "meshes", "icosphere.obj"), "w") as f:
        f.write("# Icosphere, two subdivisions, unit radius, with vertex normals.\n")
        for v in verts:
            f.write("v %.9f %.9f %.9f\n" % v)
        for v in verts:
            f.write("vn %.9f %.9f %.9f\n" % v)
        for a, b, c in faces:
            f.write(f"f {a+1}//{a+1} {b+1}//{b+1} {c+1}//{c+1}\n")


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    mesh()
    cameras()
    primitives()
    hierarchy()
    shading()
    localized()
    print(len([f for f in os.listdir(OUT) if f.endswith(".toml")]), "scenes in", os.path.relpath(OUT, ROOT))
