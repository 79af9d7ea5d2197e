"""Blender's cloth solver on weft's simulation input, for `weft bench simulate` to be
compared with on the same machine (docs/benchmarks.md).

    weft simulate --garment G.obj --motion walk --material silk --frames 31 --usd --out R
    tools/blender/.venv/bin/python tools/blender/cloth_bench.py R/scene.usda [--frames 30]

R/scene.usda holds the garment and the posed body as time-sampled meshes. The cloth
starts from weft's garment at frame 0 (after weft's warm-up) with Blender's Silk preset
and collides with the body's frames 1..FRAMES (a Collision modifier on the imported,
cached body). The waist is not pinned: Blender's pins hold vertices in the garment
object's own space, which cannot follow a cached body. Prints the mean wall time per
frame over frames 2.. and the edge strain `|l/l̄ − 1|` against the frame-0 garment.
`--no-cloth` times the body cache alone.
"""
import argparse
import sys
import time

import bpy

ap = argparse.ArgumentParser()
ap.add_argument("scene")
ap.add_argument("--frames", type=int, default=30)
ap.add_argument("--no-cloth", action="store_true")
args = ap.parse_args(sys.argv[1:])

bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
bpy.ops.wm.usd_import(filepath=args.scene)
meshes = {o.name.lower(): o for o in bpy.data.objects if o.type == "MESH"}
garment = next(o for n, o in meshes.items() if "garment" in n)
body = next(o for n, o in meshes.items() if "body" in n)
sc.frame_start, sc.frame_end = 0, args.frames
sc.render.fps = 30
sc.frame_set(0)
# The garment of frame 0 as a static mesh: its own cache modifier goes.
dg = bpy.context.evaluated_depsgraph_get()
mesh = bpy.data.meshes.new_from_object(garment.evaluated_get(dg))
for m in list(garment.modifiers):
    garment.modifiers.remove(m)
garment.data = mesh
rest = [v.co.copy() for v in mesh.vertices]
edges = [tuple(e.vertices) for e in mesh.edges]
rest_len = [(rest[a] - rest[b]).length for a, b in edges]
body.modifiers.new("Collision", "COLLISION")
if not args.no_cloth:
    cloth = garment.modifiers.new("Cloth", "CLOTH")
    s = cloth.settings
    # scripts/presets/cloth/Silk.py of Blender 5.0.
    s.quality = 5
    s.mass = 0.150
    s.tension_stiffness = s.compression_stiffness = s.shear_stiffness = 5
    s.bending_stiffness = 0.05
    s.tension_damping = s.compression_damping = s.shear_damping = 0
    s.air_damping = 1
    cloth.point_cache.frame_start = 0
    cloth.point_cache.frame_end = args.frames
times, strains = [], []
for f in range(1, args.frames + 1):
    t = time.perf_counter()
    sc.frame_set(f)
    co = [v.co.copy() for v in garment.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.vertices]
    times.append(time.perf_counter() - t)
    strains.extend(abs((co[a] - co[b]).length / l - 1.0) for (a, b), l in zip(edges, rest_len))
strains.sort()
print(
    f"blender {bpy.app.version_string}: {len(mesh.vertices)} vertices, {args.frames} frames"
    f"{' (no cloth)' if args.no_cloth else ''}: {sum(times[1:]) / max(1, len(times) - 1):.3f} s per frame;"
    f" strain mean {100 * sum(strains) / len(strains):.3f} %, p99 {100 * strains[int(0.99 * len(strains))]:.3f} %"
)
