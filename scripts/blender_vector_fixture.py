"""Renders tests/fixtures/blender_vector: two frames of a small Cycles scene (a checkered floor,
a cube that moves on its own, a camera that pans) as the multi-layer EXRs a Blender user writes
(Combined, Denoising Albedo/Normal/Depth, Vector). The test `blender_vector_pass_warps_the_previous_frame_onto_the_current`
in tests/engine/io.rs reads them with rae-core and checks the Vector pass's conversion to rae's
motion convention against the render itself: the previous frame fetched at x + motion matches the
current frame far better than with no warp or any other sign.

    python3 -m pip install bpy==4.5.15     # Blender as a Python module (Python 3.11)
    python3 scripts/blender_vector_fixture.py [OUT_DIR]

Combined at 256 spp (nearly noise-free, so the comparison measures alignment, not noise), 48x48,
frames 1 and 2, about 20 s on 2 cores. Files are written under a temporary name and renamed.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import bpy

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "blender_vector")
SIZE, SPP = 48, 256


def scene() -> bpy.types.Scene:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.device = "CPU"
    s.cycles.samples = SPP
    s.cycles.use_denoising = False
    s.cycles.seed = 1
    s.render.resolution_x = s.render.resolution_y = SIZE
    s.render.resolution_percentage = 100
    s.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    s.render.image_settings.color_depth = "32"
    s.render.image_settings.exr_codec = "ZIP"
    s.render.use_motion_blur = False
    layer = s.view_layers[0]
    layer.use_pass_vector = True
    layer.cycles.denoising_store_passes = True

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.3
    s.world = world

    # A checkered floor: texture everywhere, so a misaligned fetch shows.
    bpy.ops.mesh.primitive_plane_add(size=20)
    floor = bpy.context.object
    mat = bpy.data.materials.new("checker")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    checker = nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 12.0
    checker.inputs["Color1"].default_value = (0.8, 0.7, 0.5, 1)
    checker.inputs["Color2"].default_value = (0.1, 0.2, 0.4, 1)
    mat.node_tree.links.new(checker.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    floor.data.materials.append(mat)

    # A cube that moves on its own (x +0.6 per frame) and uncovers the floor behind it.
    bpy.ops.mesh.primitive_cube_add(size=1.2, location=(-0.6, 0, 0.6))
    cube = bpy.context.object
    red = bpy.data.materials.new("red")
    red.use_nodes = True
    red.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.1, 0.1, 1)
    cube.data.materials.append(red)
    for frame, x in ((1, -0.6), (2, 0.0)):
        cube.location.x = x
        cube.keyframe_insert("location", frame=frame)

    bpy.ops.object.light_add(type="SUN", rotation=(0.6, 0.2, 0.5))
    bpy.context.object.data.energy = 3.0

    # A camera that pans (and moves) between the frames.
    bpy.ops.object.camera_add(location=(0, -7, 5), rotation=(0.95, 0, 0))
    cam = bpy.context.object
    s.camera = cam
    for frame, (x, rz) in ((1, (0.0, 0.0)), (2, (0.35, 0.05))):
        cam.location.x = x
        cam.rotation_euler.z = rz
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    for obj in (cube, cam):
        for fc in obj.animation_data.action.fcurves if hasattr(obj.animation_data.action, "fcurves") else []:
            for k in fc.keyframe_points:
                k.interpolation = "LINEAR"
    return s


def main() -> None:
    s = scene()
    OUT.mkdir(parents=True, exist_ok=True)
    for frame in (1, 2):
        s.frame_set(frame)
        tmp = OUT / f".frame_{frame:04}.partial.exr"
        s.render.filepath = str(tmp)
        bpy.ops.render.render(write_still=True)
        os.replace(tmp, OUT / f"frame_{frame:04}.exr")
        print(f"wrote {OUT / f'frame_{frame:04}.exr'}")


if __name__ == "__main__":
    main()
