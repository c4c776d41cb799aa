"""Run by tests/test_blender.py under Blender's Python (the ``bpy`` module, in .venv-blender).

Usage: ``python blender_probe.py FILE FPS FRAME...``. Imports FILE (``.usd*`` or ``.glb``) into
an empty Blender scene whose frame rate is FPS (what docs/export.md tells users to set), and
prints one JSON object: the scene's frame rate and range after the import and, for each FRAME,
the world positions [Blender metres, Z up] of what visviva drew: the vertices of meshes, the
points of point clouds, and the locations of the moving spheres (objects named ``point_*``).
"""

import json
import sys

import bpy


def positions(scene, depsgraph):
    found = {}
    for obj in sorted(scene.objects, key=lambda o: o.name):
        evaluated = obj.evaluated_get(depsgraph)
        if obj.name.startswith("point_"):  # a glTF body: the sphere's centre
            found.setdefault("bodies", []).append(list(evaluated.matrix_world.translation))
        elif obj.type == "MESH":
            world = evaluated.matrix_world
            found[obj.name] = [list(world @ v.co) for v in evaluated.data.vertices]
        elif obj.type == "POINTCLOUD":
            world = evaluated.matrix_world
            points = evaluated.data.attributes["position"].data
            found[obj.name] = [list(world @ p.vector) for p in points]
    return found


def main():
    path, fps, *frames = sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = int(fps), 1.0
    if path.endswith((".glb", ".gltf")):
        bpy.ops.import_scene.gltf(filepath=path)
    else:
        bpy.ops.wm.usd_import(filepath=path)
    report = {"fps": scene.render.fps, "range": [scene.frame_start, scene.frame_end], "frames": {}}
    for frame in map(int, frames):
        scene.frame_set(frame)
        report["frames"][frame] = positions(scene, bpy.context.evaluated_depsgraph_get())
    print("PROBE " + json.dumps(report))


main()
