"""Opens weft's exports in Blender and checks them: the .glb has one shape key per frame
and an animation, and the PC2 played through the Mesh Cache modifier reproduces the OBJ
frames. Paths are those of the recipe in docs/blender.md ("Checked in Blender").

    blender -b --python tools/blender/check_export.py
"""
import numpy
if not hasattr(numpy, "bool"): numpy.bool = bool  # Debian blender 3.4 glTF add-on vs numpy >= 1.24
import bpy, struct
# 1. glb: one mesh with a shape key per frame, animated.
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath="/tmp/walk.glb")
meshes = [o for o in bpy.context.scene.objects if o.type == 'MESH']
for o in meshes:
    keys = o.data.shape_keys.key_blocks if o.data.shape_keys else []
    print("GLB mesh", o.name, "vertices", len(o.data.vertices), "shape keys", len(keys))
    sk = o.data.shape_keys
    print("GLB animated:", bool(sk and sk.animation_data and sk.animation_data.action))
# 2. PC2 through the Mesh Cache modifier on the template OBJ.
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath="/tmp/walkframes/frame_00000.obj", forward_axis='NEGATIVE_Z', up_axis='Y')
obj = bpy.context.scene.objects[0]
print("OBJ vertices", len(obj.data.vertices))
mod = obj.modifiers.new("cache", 'MESH_CACHE')
mod.cache_format = 'PC2'
mod.filepath = "/tmp/walk.pc2"
mod.frame_start = 1
scene = bpy.context.scene
# frame 31 in Blender = sample 30 with frame_start 1
scene.frame_set(31)
dg = bpy.context.evaluated_depsgraph_get()
ev = obj.evaluated_get(dg)
m = ev.to_mesh()
# compare with frame_00030.obj positions (raw file coordinates)
ref = [tuple(map(float, l.split()[1:4])) for l in open("/tmp/walkframes/frame_00030.obj") if l.startswith("v ")]
err = max(max(abs(a - b) for a, b in zip(v.co, r)) for v, r in zip(m.vertices, ref))
print("PC2 frame 30 vertices", len(m.vertices), "max abs diff vs frame_00030.obj", err)
