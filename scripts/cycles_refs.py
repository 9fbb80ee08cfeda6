#!/usr/bin/env python3
"""Renders Blender Cycles references for one scene exported by the conformance crate
(`conformance/src/cycles/`, a JSON file already in Blender's frame and units: see
conformance/docs/cycles.md). Runs in the Python that has `bpy` (Blender as a module,
PyPI `bpy==5.0.1`; scripts/regen-cycles.sh installs it into a venv).

    cycles_refs.py geometry SCENE.json OUT.exr SPP
        One render with a Gaussian pixel filter 0.01 px wide (Cycles' narrowest), so that every
        sample is within 0.005 px of the pixel centre, and max bounces 0. Writes a
        multilayer EXR whose AOVs `ng` (outward geometric normal: True Normal times
        1 - 2 Backfacing) and `pos` (world position) are means over SPP samples, and whose
        Object Index (from the first sample) is 1 on every object.
    cycles_refs.py radiance SCENE.json PREFIX SPP SEEDS
        SEEDS renders with a box pixel filter one pixel wide, SPP samples each, seeds 0 to
        SEEDS - 1, written to PREFIX.seed<k>.exr; each EXR's Combined pass is that seed's
        mean radiance (linear Rec.709, Standard view transform).
    cycles_refs.py version
"""
import json
import math
import sys

import bpy


def fail(msg):
    sys.stderr.write(msg + "\n")
    sys.exit(2)


def matrix(values):
    from mathutils import Matrix

    if len(values) != 16:
        fail(f"a matrix needs 16 values, got {len(values)}")
    return Matrix([values[0:4], values[4:8], values[8:12], values[12:16]])


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    return scene


def settings(scene, desc, mode, spp, seed):
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = desc["width"]
    r.resolution_y = desc["height"]
    r.resolution_percentage = 100
    r.pixel_aspect_x = 1.0
    r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_persistent_data = False
    r.use_compositing = False
    r.threads_mode = "AUTO"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.seed = seed
    c.use_animated_seed = False
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.time_limit = 0.0
    # Clamping off (the indirect default is 10, a bias), no light threshold (the default
    # 0.01 drops dim light samples), no filter glossy (the default 1.0 blurs sharp
    # reflections after a diffuse bounce), caustics on, no path guiding.
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.use_guiding = False
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    bounces = 0 if mode == "geometry" else desc["max_bounces"]
    c.max_bounces = bounces
    c.diffuse_bounces = bounces
    c.glossy_bounces = bounces
    c.transmission_bounces = bounces
    c.transparent_max_bounces = bounces
    c.volume_bounces = 0
    # Cycles forces a box filter to 1 px (intern/cycles/blender/sync.cpp, sync_film):
    # radiance uses it (uniform over the pixel, as ours); geometry uses a Gaussian 0.01 px
    # wide, its narrowest, so every sample lies within 0.005 px of the pixel centre.
    c.pixel_filter_type = "GAUSSIAN" if mode == "geometry" else "BOX"
    c.filter_width = 0.01 if mode == "geometry" else 1.0
    v = scene.view_settings
    v.view_transform = "Standard"
    v.look = "None"
    v.exposure = 0.0
    v.gamma = 1.0
    scene.display_settings.display_device = "sRGB"
    scene.sequencer_colorspace_settings.name = "Linear Rec.709"
    s = r.image_settings
    s.media_type = "MULTI_LAYER_IMAGE"
    s.file_format = "OPEN_EXR_MULTILAYER"
    s.color_depth = "32"
    s.exr_codec = "ZIP"
    layer = scene.view_layers[0]
    layer.use_pass_combined = True
    layer.use_pass_object_index = mode == "geometry"
    for name in ("ng", "pos"):
        if mode == "geometry":
            aov = layer.aovs.add()
            aov.name = name
            aov.type = "COLOR"


def camera(scene, desc):
    cam = desc["camera"]
    data = bpy.data.cameras.new("camera")
    data.type = "PERSP"
    data.lens_unit = "MILLIMETERS"
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = cam["sensor_width"]
    data.lens = cam["lens"]
    data.shift_x = cam["shift_x"]
    data.shift_y = cam["shift_y"]
    data.clip_start = cam["clip_start"]
    data.clip_end = cam["clip_end"]
    obj = bpy.data.objects.new("camera", data)
    obj.matrix_world = matrix(cam["matrix"])
    scene.collection.objects.link(obj)
    scene.camera = obj


def material(index, m, aov_normal):
    mat = bpy.data.materials.new(f"m{index}{aov_normal}")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    kind = m["type"]
    if kind == "diffuse":
        bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = (*m["color"], 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
    elif kind == "mirror":
        bsdf = nt.nodes.new("ShaderNodeBsdfGlossy")
        bsdf.distribution = "GGX"
        bsdf.inputs["Color"].default_value = (*m["color"], 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
    elif kind == "glass":
        bsdf = nt.nodes.new("ShaderNodeBsdfGlass")
        bsdf.distribution = "GGX"
        bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
        bsdf.inputs["IOR"].default_value = m["ior"]
    else:
        fail(f"material {index}: unknown type '{kind}'")
    shader = bsdf.outputs["BSDF"]
    emission = m.get("emission")
    if emission is not None:
        # One-sided emission: the back of an emitter is black (our area lights emit on
        # the side their normal points to; Cycles' Emission shader emits on both).
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (*emission, 1.0)
        em.inputs["Strength"].default_value = 1.0
        black = nt.nodes.new("ShaderNodeBsdfDiffuse")
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
        nt.links.new(em.outputs["Emission"], mix.inputs[1])
        nt.links.new(black.outputs["BSDF"], mix.inputs[2])
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(mix.outputs["Shader"], add.inputs[1])
        shader = add.outputs["Shader"]
        mat.cycles.emission_sampling = "FRONT"
    nt.links.new(shader, out.inputs["Surface"])
    # Geometry AOVs: the outward geometric normal (Cycles turns Ng towards the ray on a
    # back face; Backfacing says when) and the position.
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    flip = nt.nodes.new("ShaderNodeMath")
    flip.operation = "MULTIPLY_ADD"
    nt.links.new(geo.outputs["Backfacing"], flip.inputs[0])
    flip.inputs[1].default_value = -2.0
    flip.inputs[2].default_value = 1.0
    scale = nt.nodes.new("ShaderNodeVectorMath")
    scale.operation = "SCALE"
    normal = "Normal" if aov_normal == "shading" else "True Normal"
    nt.links.new(geo.outputs[normal], scale.inputs[0])
    nt.links.new(flip.outputs["Value"], scale.inputs["Scale"])
    for name, socket in (("ng", scale.outputs["Vector"]), ("pos", geo.outputs["Position"])):
        aov = nt.nodes.new("ShaderNodeOutputAOV")
        aov.aov_name = name
        nt.links.new(socket, aov.inputs["Color"])
    return mat


def place(scene, obj, values):
    """Places `obj` by a full affine matrix. Assigning `matrix_world` would decompose it
    into location, rotation and scale and lose any shear; the parent inverse matrix keeps
    all 16 numbers, and world = parent (identity) @ parent inverse @ basis (identity)."""
    root = scene.get("root")
    if root is None:
        root = bpy.data.objects.new("root", None)
        scene.collection.objects.link(root)
        scene["root"] = root
    obj.parent = root
    obj.matrix_parent_inverse = matrix(values)


def objects(scene, desc, materials):
    for k, o in enumerate(desc["objects"]):
        name = f"o{k}"
        shape = o["shape"]
        if shape == "mesh":
            mesh = bpy.data.meshes.new(name)
            p = o["positions"]
            t = o["triangles"]
            verts = [p[i : i + 3] for i in range(0, len(p), 3)]
            faces = [t[i : i + 3] for i in range(0, len(t), 3)]
            mesh.from_pydata(verts, [], faces)
            normals = o.get("normals")
            if normals:
                mesh.shade_smooth()
                mesh.normals_split_custom_set_from_vertices(
                    [normals[i : i + 3] for i in range(0, len(normals), 3)]
                )
            else:
                mesh.shade_flat()
            mesh.validate()
            data = mesh
        elif shape == "icosphere":
            # Blender's icosphere of radius 1 (vertices on the sphere), shaded with the
            # radial direction at each vertex: the interpolated normal of a point on a face
            # is then the direction of that point from the centre.
            import bmesh

            data = bpy.data.meshes.new(name)
            bm = bmesh.new()
            bmesh.ops.create_icosphere(bm, subdivisions=o["subdivisions"], radius=1.0)
            bm.to_mesh(data)
            bm.free()
            data.shade_smooth()
            data.normals_split_custom_set_from_vertices(
                [v.co.normalized() for v in data.vertices]
            )
        elif shape == "sphere":
            # One vertex turned into one point of radius 1 by geometry nodes (Mesh to
            # Points): Cycles intersects a point cloud's points as exact spheres.
            data = bpy.data.meshes.new(name)
            data.from_pydata([(0.0, 0.0, 0.0)], [], [])
        else:
            fail(f"object {k}: unknown shape '{shape}'")
        kind = o.get("aov_normal", "true")
        key = (o["material"], kind)
        if key not in materials:
            materials[key] = material(o["material"], desc["materials"][o["material"]], kind)
        data.materials.append(materials[key])
        obj = bpy.data.objects.new(name, data)
        if shape == "sphere":
            points(obj, materials[key])
        place(scene, obj, o["matrix"])
        obj.pass_index = 1
        # Cycles moves shadow rays off smooth-shaded low-poly surfaces by default
        # (shadow terminator geometry offset 0.1), a deliberate bias: off.
        obj.shadow_terminator_geometry_offset = 0.0
        obj.shadow_terminator_shading_offset = 0.0
        obj.shadow_terminator_normal_offset = 0.0
        scene.collection.objects.link(obj)


def points(obj, mat):
    # A sphere under a similarity only: Cycles bakes a one-user point's transform into
    # its centre and radius (intern/cycles/scene/pointcloud.cpp, apply_transform), exact
    # for a similarity; any other map is exported as an icosphere mesh (export.rs).
    group = bpy.data.node_groups.new(obj.name + "-points", "GeometryNodeTree")
    group.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    group.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes = group.nodes
    gin = nodes.new("NodeGroupInput")
    gout = nodes.new("NodeGroupOutput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.mode = "VERTICES"
    to_points.inputs["Radius"].default_value = 1.0
    set_mat = nodes.new("GeometryNodeSetMaterial")
    set_mat.inputs["Material"].default_value = mat
    group.links.new(gin.outputs[0], to_points.inputs["Mesh"])
    group.links.new(to_points.outputs["Points"], set_mat.inputs["Geometry"])
    group.links.new(set_mat.outputs["Geometry"], gout.inputs[0])
    mod = obj.modifiers.new("points", "NODES")
    mod.node_group = group


def lights(scene, desc):
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    nt = world.node_tree
    bg = next(n for n in nt.nodes if n.type == "BACKGROUND")
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world
    for k, l in enumerate(desc["lights"]):
        kind = l["type"]
        if kind == "world":
            bg.inputs["Color"].default_value = (*l["radiance"], 1.0)
            continue
        if kind == "point":
            data = bpy.data.lights.new(f"l{k}", "POINT")
            data.shadow_soft_size = 0.0
            data.use_soft_falloff = False
        elif kind == "sun":
            data = bpy.data.lights.new(f"l{k}", "SUN")
            data.angle = 0.0
        else:
            fail(f"light {k}: unknown type '{kind}'")
        data.color = l["color"]
        data.energy = l["energy"]
        obj = bpy.data.objects.new(f"l{k}", data)
        obj.matrix_world = matrix(l["matrix"])
        scene.collection.objects.link(obj)


def build(path, mode, spp, seed):
    with open(path) as f:
        desc = json.load(f)
    scene = reset()
    settings(scene, desc, mode, spp, seed)
    camera(scene, desc)
    objects(scene, desc, {})
    lights(scene, desc)
    return scene


def render(scene, out):
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    cmd = sys.argv[1] if len(sys.argv) > 1 else ""
    if cmd == "geometry" and len(sys.argv) == 5:
        render(build(sys.argv[2], "geometry", int(sys.argv[4]), 0), sys.argv[3])
    elif cmd == "radiance" and len(sys.argv) == 6:
        scene = build(sys.argv[2], "radiance", int(sys.argv[4]), 0)
        for seed in range(int(sys.argv[5])):
            scene.cycles.seed = seed
            render(scene, f"{sys.argv[3]}.seed{seed}.exr")
    elif cmd == "version":
        print(bpy.app.version_string)
    else:
        sys.exit(__doc__)
