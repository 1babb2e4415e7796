"""Renders a glTF file with Blender's Cycles through its Python module (`pip install bpy`;
Blender's own glTF importer), black world, the file's first camera: the Cycles half of
docs/img/clearcoat_side_by_side.png (scripts/clearcoat_scene.py writes the scene).

usage: python clearcoat_cycles.py IN.gltf OUT.png WIDTH HEIGHT SAMPLES
"""
import sys

import bpy


def main(src, out, width, height, samples):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=src)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 10
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world
    scene.camera = next(o for o in scene.objects if o.type == "CAMERA")
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    a = sys.argv[1:]
    main(a[0], a[1], int(a[2]), int(a[3]), int(a[4]))
