"""Imports a weft output into the current Blender scene (needs bpy; see detect.py for what
is recognised and __init__.py for the operator).

One convention for every route: weft's sample k is shown at scene frame 1 + k, so the
scene range is 1..frames (docs/blender.md):

- GLTF: Blender's glTF importer, then every key it made is moved from time t (seconds)
  to frame 1 + t * fps. The importer places keys at t * render.fps * render.fps_base
  (Blender 5.0's io_scene_gltf2/blender/imp/animation_weight.py), which is wrong for a
  rate like 23.976 (fps 24, fps_base 1.001); importing at exactly 1 fps and moving the
  keys here gives exact frames for every rate.
- USD: Blender's USD importer (a Mesh Sequence Cache modifier streams the time-sampled
  points), with the cache file's Frame Offset set so time code `start` is frame 1.
- MESH_CACHE: the rest OBJ (vertex order kept, Y up on the object) with a Mesh Cache
  modifier reading the PC2/MDD in Frame time mode, Frame Start 1.
"""

import os
import re

import bpy

from .detect import WeftImportError, plan as make_plan, scene_rate

ROLES = ("garment", "body")


def _op_kwargs(op, **kwargs):
    """The keyword arguments `op` knows in this Blender version (importers gain and lose
    options between releases)."""
    known = op.get_rna_type().properties.keys()
    return {k: v for k, v in kwargs.items() if k in known}


def _run(op, what, source, **kwargs):
    try:
        result = op(**_op_kwargs(op, **kwargs))
    except RuntimeError as e:
        # bpy.ops turns an importer's error report into RuntimeError("Error: ...").
        msg = str(e).strip().replace("\n", " ")
        raise WeftImportError("%s: Blender's %s importer failed: %s" % (source, what, msg)) from None
    if "FINISHED" not in result:
        raise WeftImportError(
            "%s: Blender's %s importer returned %s" % (source, what, ", ".join(sorted(result)))
        )


def _fcurves(action):
    """Every F-curve of an action: layered actions (Blender 4.4+, the only kind in 5.0)
    keep them in channel bags, older ones in action.fcurves."""
    layers = getattr(action, "layers", None)
    if layers:
        for layer in layers:
            for strip in layer.strips:
                for bag in getattr(strip, "channelbags", ()):
                    yield from bag.fcurves
        return
    yield from getattr(action, "fcurves", ())


def _retime(action, fps):
    """Keys at t seconds (imported at 1 fps) to frame 1 + t * fps; a key within 1e-3 of a
    whole frame lands on it exactly, so a STEP key at 3.0000002 still shows at frame 3."""
    for fc in _fcurves(action):
        for k in fc.keyframe_points:
            x0, y0 = k.co[0], k.co[1]
            x = 1.0 + x0 * fps
            if abs(x - round(x)) < 1e-3:
                x = float(round(x))
            hl, hr = k.handle_left[:], k.handle_right[:]
            k.co = (x, y0)
            k.handle_left = (x + (hl[0] - x0) * fps, hl[1])
            k.handle_right = (x + (hr[0] - x0) * fps, hr[1])
        fc.update()


def _import_gltf(p, scene):
    saved = (scene.render.fps, scene.render.fps_base)
    actions = set(bpy.data.actions)
    scene.render.fps, scene.render.fps_base = 1, 1.0
    try:
        _run(bpy.ops.import_scene.gltf, "glTF", p.source, filepath=p.source)
    finally:
        scene.render.fps, scene.render.fps_base = saved
    if p.fps:
        for action in set(bpy.data.actions) - actions:
            _retime(action, p.fps)


def _import_usd(p, scene):
    saved = (scene.frame_start, scene.frame_end)
    caches = set(bpy.data.cache_files)
    try:
        _run(bpy.ops.wm.usd_import, "USD", p.source, filepath=p.source, set_frame_range=True)
        if p.frames is None and scene.frame_end >= scene.frame_start:
            # A binary stage: the importer read its start and end time codes.
            p.start = float(scene.frame_start)
            p.frames = scene.frame_end - scene.frame_start + 1
    finally:
        scene.frame_start, scene.frame_end = saved
    for cache in set(bpy.data.cache_files) - caches:
        # Looked up at (scene frame - offset): time code `start` at frame 1.
        cache.frame_offset = 1.0 - p.start


def _import_mesh_cache(p, scene):
    before = set(bpy.data.objects)
    if p.mesh.lower().endswith(".ply"):
        _run(
            bpy.ops.wm.ply_import, "PLY", p.mesh,
            filepath=p.mesh, forward_axis="NEGATIVE_Z", up_axis="Y", merge_verts=False,
        )
    else:
        # One object, every vertex in file order: what a cache addresses by index.
        _run(
            bpy.ops.wm.obj_import, "OBJ", p.mesh,
            filepath=p.mesh, forward_axis="NEGATIVE_Z", up_axis="Y",
            use_split_objects=False, use_split_groups=False, validate_meshes=False,
        )
    made = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if len(made) != 1:
        raise WeftImportError(
            "%s: Blender's importer made %d meshes of it; a point cache needs exactly one"
            % (p.mesh, len(made))
        )
    obj = made[0]
    if len(obj.data.vertices) != p.points:
        raise WeftImportError(
            "%s: imported with %d vertices, but %s moves %d"
            % (p.mesh, len(obj.data.vertices), p.source, p.points)
        )
    obj.name = "garment"
    mod = obj.modifiers.new("weft %s" % p.cache_format, "MESH_CACHE")
    mod.cache_format = p.cache_format
    mod.filepath = p.source
    mod.time_mode = "FRAME"
    mod.play_mode = "SCENE"
    mod.frame_start = 1.0  # sample 0 at scene frame 1
    mod.frame_scale = 1.0
    mod.forward_axis, mod.up_axis = "POS_Y", "POS_Z"  # the cache is in the OBJ's own axes


_SUFFIX = re.compile(r"\.\d{3,}$")


def _name_roles(objects, hinted):
    """{'garment': obj, 'body': obj} among the new meshes: by name (weft names them), the
    only mesh being the garment."""
    meshes = [o for o in objects if o.type == "MESH"]
    roles = {}
    for o in meshes:
        base = _SUFFIX.sub("", o.name)
        if base in ROLES and base not in roles:
            roles[base] = o
    if "garment" not in roles:
        rest = [o for o in meshes if o not in roles.values()]
        if len(rest) == 1:
            roles["garment"] = rest[0]
        elif hinted and hinted[0] in [_SUFFIX.sub("", o.name) for o in rest]:
            roles["garment"] = next(o for o in rest if _SUFFIX.sub("", o.name) == hinted[0])
    for role, o in roles.items():
        if o.name != role:
            o.name = role  # Blender appends .001 when another object already has it
        if o.data.users == 1 and o.data.name != o.name:
            o.data.name = o.name
    return roles


def _collect(objects, name, scene, collections_before):
    coll = bpy.data.collections.new(name)
    scene.collection.children.link(coll)
    for o in objects:
        for c in list(o.users_collection):
            c.objects.unlink(o)
        coll.objects.link(o)
    # Collections an importer made for itself (glTF's "scene as collection"), now empty.
    for c in list(bpy.data.collections):
        if c not in collections_before and c is not coll and not c.objects and not c.children:
            bpy.data.collections.remove(c)
    return coll


def _discard(objects, collections_before):
    for o in objects:
        try:
            bpy.data.objects.remove(o)
        except ReferenceError:
            pass
    for c in list(bpy.data.collections):
        if c not in collections_before and not c.objects and not c.children:
            bpy.data.collections.remove(c)


def import_directory(path, method="AUTO", set_scene=True, context=None):
    """Import a weft output directory (or one .glb/.gltf/.usd*/.pc2/.mdd file of one) into
    the current scene and return what was done:

    {"directory", "layout" (simulate|demo|export), "method" (GLTF|USD|MESH_CACHE),
     "source" (the file imported), "mesh" (MESH_CACHE: the rest mesh), "collection",
     "objects" ({"garment": name, "body": name or None}), "vertices" ({role: count}),
     "fps", "fps_source", "frames", "frame_start", "frame_end", "alternatives",
     "notes", "summary"}

    method: "AUTO" (glTF, else USD, else the point cache), "GLTF", "USD" or "MESH_CACHE".
    set_scene: set the scene's frame rate (fps / fps_base) and range 1..frames.
    Raises WeftImportError, whose message names the file, when there is nothing to import
    or an importer fails; the scene is left as it was then.
    """
    context = context or bpy.context
    scene = context.scene
    p = make_plan(path, method)
    objects_before = set(bpy.data.objects)
    collections_before = set(bpy.data.collections)
    made = []
    try:
        if p.method == "GLTF":
            _import_gltf(p, scene)
        elif p.method == "USD":
            _import_usd(p, scene)
        else:
            _import_mesh_cache(p, scene)
        made = [o for o in bpy.data.objects if o not in objects_before]
        if not any(o.type == "MESH" for o in made):
            raise WeftImportError("%s: Blender's importer made no mesh of it" % p.source)
        roles = _name_roles(made, p.mesh_names)
        if "garment" not in roles:
            p.notes.append(
                "no mesh is named garment or body (%s): names kept"
                % ", ".join(o.name for o in made if o.type == "MESH")
            )
        name = os.path.basename(os.path.normpath(p.directory)) or "weft"
        coll = _collect(made, name, scene, collections_before)
    except Exception:
        _discard([o for o in bpy.data.objects if o not in objects_before], collections_before)
        raise

    if set_scene:
        if p.fps:
            scene.render.fps, scene.render.fps_base = scene_rate(p.fps)
        if p.frames:
            scene.frame_start, scene.frame_end = 1, p.frames
        scene.frame_set(1)
    if "body" not in roles and p.method == "MESH_CACHE":
        others = [m for m in p.alternatives if m in ("GLTF", "USD")]
        p.notes.append(
            "no body: a point cache holds the garment only"
            + (" (the %s route brings the body too)" % " or ".join(others) if others else "")
        )
    try:
        for o in made:
            o.select_set(True)
        if "garment" in roles:
            context.view_layer.objects.active = roles["garment"]
    except (RuntimeError, AttributeError):
        pass  # no view layer to select in (some headless contexts)

    rate = scene.render.fps / scene.render.fps_base
    objects = {r: (roles[r].name if r in roles else None) for r in ROLES}
    vertices = {r: len(o.data.vertices) for r, o in roles.items()}
    if set_scene or not p.fps:
        timing = "scene at %g fps" % rate
    else:
        timing = "recorded at %g fps, scene kept at %g fps" % (p.fps, rate)
    summary = "%s: %s of %s into collection %s: %s; %s frames (scene frames %s), %s" % (
        p.directory,
        {"GLTF": "glTF", "USD": "USD", "MESH_CACHE": "%s point cache on the rest mesh" % p.cache_format}[p.method],
        os.path.basename(p.source),
        coll.name,
        ", ".join("%s (%d vertices)" % (objects[r], vertices[r]) for r in ROLES if r in roles)
        or ", ".join(o.name for o in made),
        p.frames if p.frames is not None else "?",
        "1-%d" % p.frames if p.frames else "?",
        timing,
    )
    return {
        "directory": p.directory,
        "layout": p.layout,
        "method": p.method,
        "source": p.source,
        "mesh": p.mesh,
        "collection": coll.name,
        "objects": objects,
        "vertices": vertices,
        "fps": p.fps,
        "fps_source": p.fps_source,
        "frames": p.frames,
        "frame_start": 1,
        "frame_end": p.frames,
        "alternatives": p.alternatives,
        "notes": p.notes,
        "summary": summary,
    }
