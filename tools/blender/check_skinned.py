"""Plays a skinned .glb from weft in Blender (PyPI bpy) and compares the garment and the
body Blender shows at every frame with the frames weft wrote.

    tools/blender/.venv/bin/python tools/blender/check_skinned.py SCENE.glb GARMENT.npy|DIR BODY.npy|DIR

The glTF importer turns the skeleton into an armature, the skin into an Armature
modifier and the corrective morph targets into shape keys; this evaluates the scene at
each frame (the depsgraph, as the viewport and renderers do) and measures, per frame,
the largest distance from any vertex Blender shows to the nearest vertex weft wrote and
back (the importer may reorder or split vertices at UV seams). Prints one JSON line
with the largest error per mesh; exits 1 when it is above 0.1 mm (or when being one
frame off would not be noticed).
"""
import json
import os
import sys

import bpy
import numpy as np
from mathutils.kdtree import KDTree


def frames_of(path):
    """`(T, N, 3)` from an .npy or a directory of OBJ frames (sorted by name)."""
    if os.path.isdir(path):
        a = np.array([
            [[float(x) for x in line.split()[1:4]] for line in open(os.path.join(path, f)) if line.startswith("v ")]
            for f in sorted(os.listdir(path)) if f.endswith(".obj")
        ])
    else:
        a = np.load(path)
    assert a.ndim == 3 and a.shape[2] == 3, a.shape
    # weft is Y up; Blender's importer converts glTF's Y up to Z up: (x, y, z) -> (x, -z, y).
    return np.stack([a[..., 0], -a[..., 2], a[..., 1]], axis=-1)


def shown(obj, depsgraph):
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    m = np.array(obj.matrix_world)
    p = np.array([v.co[:] for v in mesh.vertices])
    ev.to_mesh_clear()
    return p @ m[:3, :3].T + m[:3, 3]


def hausdorff(a, b):
    def one_way(x, y):
        tree = KDTree(len(y))
        for i, q in enumerate(y):
            tree.insert(q, i)
        tree.balance()
        return max(tree.find(q)[2] for q in x)
    return max(one_way(a, b), one_way(b, a))


def main():
    glb, garment_npy, body_npy = sys.argv[1:4]
    expected = {"garment": frames_of(garment_npy), "body": frames_of(body_npy)}
    with open(glb, "rb") as f:
        data = f.read()
    rate = json.loads(data[20:20 + int.from_bytes(data[12:16], "little")])["asset"]["extras"]["fps"]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    # The importer keys time t at scene frame t × the scene's rate: at the file's own
    # rate, weft's frame k is scene frame k.
    scene.render.fps, scene.render.fps_base = int(round(rate)), round(rate) / rate
    bpy.ops.import_scene.gltf(filepath=glb)
    meshes = {o.name.split(".")[0]: o for o in scene.objects if o.type == "MESH"}
    frames = expected["garment"].shape[0]
    worst = {}
    for name, exp in expected.items():
        obj = meshes[name]
        errors = []
        for k in range(frames):
            scene.frame_set(k)
            depsgraph = bpy.context.evaluated_depsgraph_get()
            errors.append(hausdorff(shown(obj, depsgraph), exp[k]))
        worst[name] = max(errors)
    # Off by one frame must fail, so the comparison can.
    scene.frame_set(1)
    off = hausdorff(shown(meshes["body"], bpy.context.evaluated_depsgraph_get()), expected["body"][0])
    print(json.dumps({"frames": frames, "fps": rate, "max_error_m": worst, "one_frame_off_m": off}))
    return 0 if max(worst.values()) < 1e-4 and off > 1e-3 else 1


if __name__ == "__main__":
    sys.exit(main())
