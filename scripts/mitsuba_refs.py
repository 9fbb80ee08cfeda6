#!/usr/bin/env python3
"""Renders Mitsuba 3 references for one exported scene: with `scalar_rgb`, or for
`radiance` and `time` with the variant MITSUBA_VARIANT names (`llvm_ad_rgb`, Mitsuba's fast
CPU variant, needs DRJIT_LIBLLVM_PATH set to a libLLVM 19: conformance/docs/mitsuba.md).
Geometry is always traced in `scalar_rgb`, one pixel-centre ray at a time.

    mitsuba_refs.py geometry SCENE.xml OUT.exr
        For every pixel, the pixel-centre ray (sensor.sample_ray) and scene.ray_intersect.
        Channels: Z (distance from the eye, |p - eye|: sensor rays start on the near clip
        plane, so si.t is not it), N.X/N.Y/N.Z (unit geometric normal, mapped back to the
        renderer's left-handed world by x -> -x), mask (1 where something is hit).
    mitsuba_refs.py radiance SCENE.xml OUT.exr SPP
        mi.render through the `moment` integrator the scene was exported with. The EXR has
        R, G, B (mean), then per-pixel XYZ first and second moments (_arg_0.* and m2__arg_0.*).
    mitsuba_refs.py time SCENE.xml OUT.exr SPP
        Renders the scene as exported (no moment integrator) and prints the seconds that
        mi.render took (scene loading excluded).
    mitsuba_refs.py version
"""
import os
import sys

import numpy as np
import mitsuba as mi

VARIANT = os.environ.get("MITSUBA_VARIANT", "scalar_rgb")


def geometry(xml, out):
    mi.set_variant("scalar_rgb")
    scene = mi.load_file(xml)
    sensor = scene.sensors()[0]
    w, h = sensor.film().size()
    eye = np.array(sensor.world_transform() @ mi.ScalarPoint3f(0, 0, 0), dtype=np.float64)
    data = np.zeros((h, w, 5), dtype=np.float32)
    for j in range(h):
        for i in range(w):
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.ScalarPoint2f((i + 0.5) / w, (j + 0.5) / h), mi.ScalarPoint2f(0.5, 0.5))
            si = scene.ray_intersect(ray)
            if si.is_valid():
                p = np.array(si.p, dtype=np.float64)
                n = np.array(si.n, dtype=np.float64)
                n /= np.linalg.norm(n)
                data[j, i] = [np.linalg.norm(p - eye), -n[0], n[1], n[2], 1.0]
    bmp = mi.Bitmap(data, mi.Bitmap.PixelFormat.MultiChannel, ["Z", "N.X", "N.Y", "N.Z", "mask"])
    bmp.write(out)


def radiance(xml, out, spp):
    mi.set_variant(VARIANT)
    scene = mi.load_file(xml)
    mi.render(scene, spp=spp, seed=0)
    scene.sensors()[0].film().bitmap(raw=False).write(out)


def timed(xml, out, spp):
    import time

    mi.set_variant(VARIANT)
    scene = mi.load_file(xml)
    t0 = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=0)
    seconds = time.perf_counter() - t0
    mi.Bitmap(image).write(out)
    print(f"{seconds:.6f}")


if __name__ == "__main__":
    cmd = sys.argv[1] if len(sys.argv) > 1 else ""
    if cmd == "geometry":
        geometry(sys.argv[2], sys.argv[3])
    elif cmd == "radiance":
        radiance(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    elif cmd == "time":
        timed(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    elif cmd == "version":
        print(mi.__version__)
    else:
        sys.exit(__doc__)
