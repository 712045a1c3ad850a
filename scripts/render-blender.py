"""Renders procedural Blender Cycles sequences the way Blender users get them: one multi-layer
EXR per frame with Combined, Denoising Albedo / Normal / Depth, Vector and a roughness AOV, plus a
`reference` layer (the same frame at many samples) for training and evaluation. `rae-cli denoise`
reads the folders as they are; `weights-tool` loads them like rae-trace's (`rae_weights.data`).

    python3 -m pip install bpy==4.5.15      # Blender as a Python module (Python 3.11)
    python3 scripts/render-blender.py OUT --seeds 2001-2004 [--frames 8] [--size 128x128] [--spp 1] [--ref-spp 256]
    python3 scripts/render-blender.py OUT4 --seeds 2001-2004 --spp 4 --reference-from OUT
    python3 scripts/render-blender.py OUT --seeds 2005,2011-2012,2038   # a list of seeds and ranges

Each seed is a scene built from primitives and procedural textures: a textured floor, three to six
objects of plastic, metal, glass or light-emitting material, a sun and zero to two area lights, a
world colour, a camera that pans and moves at a speed drawn per sequence (still to fast), and one
object that moves on its own. Blender's conventions are kept (camera-space normals, ray-length
depth with 0 at misses, Vector in Blender's sign and y up, Blackman-Harris pixel filter):
`../shared/BLENDER.md`. Noise is fresh per frame (`use_animated_seed`). Every file is written
under a temporary name and renamed; a sequence already complete is skipped, so an interrupted run
continues.
"""

from __future__ import annotations

import argparse
import math
import os
import random
import shutil
import sys
from pathlib import Path

import bpy
import numpy as np
import OpenEXR


def material(name: str, rng: random.Random) -> tuple[bpy.types.Material, str]:
    """A random Principled material with its roughness written to the `roughness` AOV."""
    kind = rng.choice(["plastic", "plastic", "metal", "glass", "emitter"])
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    color = (rng.uniform(0.05, 0.9), rng.uniform(0.05, 0.9), rng.uniform(0.05, 0.9), 1.0)
    rough = {"plastic": rng.uniform(0.2, 0.8), "metal": rng.uniform(0.05, 0.4), "glass": 0.0, "emitter": 0.5}[kind]
    bsdf.inputs["Base Color"].default_value = color
    bsdf.inputs["Roughness"].default_value = rough
    if kind == "metal":
        bsdf.inputs["Metallic"].default_value = 1.0
    elif kind == "glass":
        bsdf.inputs["Transmission Weight"].default_value = 1.0
        bsdf.inputs["IOR"].default_value = 1.45
    elif kind == "emitter":
        bsdf.inputs["Emission Color"].default_value = color
        bsdf.inputs["Emission Strength"].default_value = rng.uniform(3.0, 15.0)
    aov = nodes.new("ShaderNodeOutputAOV")
    aov.aov_name = "roughness"
    value = nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = rough
    links.new(value.outputs[0], aov.inputs["Value"])
    return mat, kind


def floor_material(rng: random.Random) -> bpy.types.Material:
    mat = bpy.data.materials.new("floor")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    tex = nodes.new(rng.choice(["ShaderNodeTexChecker", "ShaderNodeTexVoronoi", "ShaderNodeTexNoise", "ShaderNodeTexBrick"]))
    tex.inputs["Scale"].default_value = rng.uniform(2.0, 20.0)
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (rng.uniform(0, 0.5), rng.uniform(0, 0.5), rng.uniform(0, 0.5), 1)
    ramp.color_ramp.elements[1].color = (rng.uniform(0.4, 0.9), rng.uniform(0.4, 0.9), rng.uniform(0.4, 0.9), 1)
    out = tex.outputs["Fac"] if "Fac" in tex.outputs else tex.outputs[0]
    links.new(out, ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    rough = rng.uniform(0.1, 0.9)
    bsdf.inputs["Roughness"].default_value = rough
    aov = nodes.new("ShaderNodeOutputAOV")
    aov.aov_name = "roughness"
    value = nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = rough
    links.new(value.outputs[0], aov.inputs["Value"])
    return mat


def build(seed: int, frames: int, size: tuple[int, int]) -> bpy.types.Scene:
    rng = random.Random(seed)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.device = "CPU"
    s.cycles.use_denoising = False
    s.cycles.use_animated_seed = True
    s.render.resolution_x, s.render.resolution_y = size
    s.render.resolution_percentage = 100
    s.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    s.render.image_settings.color_depth = "32"
    s.render.image_settings.exr_codec = "ZIP"
    s.render.use_motion_blur = False
    s.frame_start, s.frame_end = 1, frames
    layer = s.view_layers[0]
    layer.use_pass_vector = True
    layer.cycles.denoising_store_passes = True
    aov = layer.aovs.add()
    aov.name, aov.type = "roughness", "VALUE"

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (rng.uniform(0.1, 0.8), rng.uniform(0.1, 0.8), rng.uniform(0.2, 1.0), 1)
    bg.inputs["Strength"].default_value = rng.uniform(0.1, 1.0)
    s.world = world

    bpy.ops.mesh.primitive_plane_add(size=40)
    bpy.context.object.data.materials.append(floor_material(rng))
    objects = []
    for i in range(rng.randint(3, 6)):
        shape = rng.choice(["cube", "sphere", "cylinder", "torus", "monkey"])
        loc = (rng.uniform(-3, 3), rng.uniform(-3, 3), 0)
        scale = rng.uniform(0.4, 1.2)
        if shape == "cube":
            bpy.ops.mesh.primitive_cube_add(size=2 * scale, location=(loc[0], loc[1], scale))
        elif shape == "sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(radius=scale, location=(loc[0], loc[1], scale))
            bpy.ops.object.shade_smooth()
        elif shape == "cylinder":
            bpy.ops.mesh.primitive_cylinder_add(radius=0.5 * scale, depth=2 * scale, location=(loc[0], loc[1], scale))
        elif shape == "torus":
            bpy.ops.mesh.primitive_torus_add(major_radius=scale, minor_radius=0.3 * scale, location=(loc[0], loc[1], 0.3 * scale))
            bpy.ops.object.shade_smooth()
        else:
            bpy.ops.mesh.primitive_monkey_add(size=1.5 * scale, location=(loc[0], loc[1], scale))
            bpy.ops.object.shade_smooth()
        obj = bpy.context.object
        obj.rotation_euler.z = rng.uniform(0, math.tau)
        mat, _ = material(f"m{i}", rng)
        obj.data.materials.append(mat)
        objects.append(obj)

    # One object moves on its own, linearly, up to 0.4 units a frame.
    mover = rng.choice(objects)
    start = mover.location.copy()
    step = (rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4))
    for f in (1, frames):
        mover.location = (start.x + step[0] * (f - 1), start.y + step[1] * (f - 1), start.z)
        mover.keyframe_insert("location", frame=f)

    bpy.ops.object.light_add(type="SUN", rotation=(rng.uniform(0.2, 1.0), rng.uniform(-0.5, 0.5), rng.uniform(0, math.tau)))
    bpy.context.object.data.energy = rng.uniform(1.0, 4.0)
    for _ in range(rng.randint(0, 2)):
        bpy.ops.object.light_add(type="AREA", location=(rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(2, 5)))
        bpy.context.object.data.energy = rng.uniform(50, 400)
        bpy.context.object.data.size = rng.uniform(0.2, 2.0)

    # The camera circles the scene's centre at a speed drawn per sequence (0 to about 4 degrees
    # a frame) and rises or sinks a little, always looking at the centre.
    target = bpy.data.objects.new("target", None)
    s.collection.objects.link(target)
    target.location = (rng.uniform(-1, 1), rng.uniform(-1, 1), 0.5)
    bpy.ops.object.camera_add()
    cam = bpy.context.object
    s.camera = cam
    track = cam.constraints.new("TRACK_TO")
    track.target = target
    angle, speed = rng.uniform(0, math.tau), rng.choice([0.0, 0.01, 0.03, 0.07])
    radius, height, rise = rng.uniform(7, 10), rng.uniform(2.5, 5), rng.uniform(-0.1, 0.1)
    for f in (1, frames):
        a = angle + speed * (f - 1)
        cam.location = (radius * math.cos(a), radius * math.sin(a), height + rise * (f - 1))
        cam.keyframe_insert("location", frame=f)
    for obj in (mover, cam):
        action = obj.animation_data.action
        for fc in getattr(action, "fcurves", []):
            for k in fc.keyframe_points:
                k.interpolation = "LINEAR"
    return s


def render(s: bpy.types.Scene, frame: int, spp: int, seed: int, path: Path) -> dict[str, np.ndarray]:
    s.cycles.samples = spp
    s.cycles.seed = seed
    s.frame_set(frame)
    s.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    with OpenEXR.File(str(path)) as f:
        return {k: np.asarray(v.pixels) for k, v in f.channels().items()}


def write(path: Path, channels: dict[str, np.ndarray]) -> None:
    tmp = path.with_name(f".{path.name}.partial.exr")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}).write(str(tmp))
    os.replace(tmp, path)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out", type=Path)
    p.add_argument("--seeds", default="2001-2004", help="scene seeds: first-last, or a comma-separated list of seeds and ranges")
    p.add_argument("--frames", type=int, default=8)
    p.add_argument("--size", default="128x128")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--ref-spp", type=int, default=256)
    p.add_argument("--reference-from", type=Path, help="copy the reference layer from this folder's sequences instead of rendering it")
    a = p.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:])
    seeds = []
    for part in a.seeds.split(","):
        first, _, last = part.partition("-")
        seeds += range(int(first), int(last or first) + 1)
    size = tuple(int(v) for v in a.size.split("x"))
    for seed in seeds:
        name = f"b{seed}"
        done = a.out / name
        if done.exists():
            continue
        work = a.out / f".{name}.partial"
        shutil.rmtree(work, ignore_errors=True)
        work.mkdir(parents=True)
        s = build(seed, a.frames, size)  # type: ignore[arg-type]
        for f in range(1, a.frames + 1):
            noisy = render(s, f, a.spp, seed * 100 + f, work / "noisy.exr")
            if a.reference_from:
                with OpenEXR.File(str(a.reference_from / name / f"frame_{f:04}.exr")) as r:
                    ref = np.asarray(r.channels()["reference"].pixels)
            else:
                ref = render(s, f, a.ref_spp, 7 + f, work / "ref.exr")["ViewLayer.Combined"][..., :3]
            noisy["reference"] = ref
            write(work / f"frame_{f:04}.exr", noisy)
            print(f"{name} frame {f}/{a.frames}", flush=True)
        for tmp in ("noisy.exr", "ref.exr"):
            (work / tmp).unlink(missing_ok=True)
        os.replace(work, done)


if __name__ == "__main__":
    main()
