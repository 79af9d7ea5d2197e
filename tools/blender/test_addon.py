"""Headless check of the weft_import add-on in Blender-as-a-module (PyPI bpy, pinned in
tools/blender/requirements.txt). crates/weft-cli/tests/blender_addon.rs makes real weft
outputs with the weft binary, writes CASES.json beside them, and runs

    tools/blender/.venv/bin/python tools/blender/test_addon.py CASES.json

CASES.json (relative paths are relative to the file's directory):

    {"cases": [
       {"path": "sim", "method": "AUTO",
        "expect": {"method": "USD", "layout": "simulate", "fps": 25, "frames": 4,
                   "collection": "sim", "garment_vertices": 480, "body_vertices": 13380,
                   "frames_npy": "sim/frames.npy"}},
       {"path": "empty", "error": "a substring the message must hold"}],
     "operator": {"ok": "sim", "fail": "empty"}}

For each case it imports with weft_import.import_directory into a fresh empty scene and
asserts what the add-on promises: the route taken, the collection named after the
directory, objects named garment/body, vertex counts, the scene's rate
(render.fps / render.fps_base) and range 1..frames, and that at scene frame 1 + k the
garment's evaluated vertices, in world space, are frame k of frames.npy turned from weft's
Y up to Blender's Z up, within 1e-5 (glTF splits vertices at UV seams, so there each
Blender vertex is matched to the template vertex it coincides with at frame 0, and every
template vertex must be matched). An error case must raise WeftImportError holding the
text and leave no object behind.

Then ("operator") it links the folder into a temporary user scripts/addons and enables
it as a legacy add-on (bl_info); on Blender 4.2+ it then disables that, packs the folder
into a zip and installs it as an extension into the same temporary user directory (the
ways a person installs it),
and runs File > Import > weft output directory's operator on a good directory and on
one that holds nothing, which must fail with one line naming it and no traceback; and
an internal failure must also reach the UI as one line.

Prints one JSON line per check and exits 1 on the first failed assertion.
"""

import atexit
import json
import os
import shutil
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
# Extensions install into BLENDER_USER_RESOURCES, read when bpy starts: a temporary
# one keeps the person's own Blender configuration out of the test.
USER_RESOURCES = tempfile.mkdtemp(prefix="weft-blender-user-")
os.environ["BLENDER_USER_RESOURCES"] = USER_RESOURCES
atexit.register(shutil.rmtree, USER_RESOURCES, True)

import bpy  # noqa: E402
import numpy as np  # noqa: E402  (numpy comes with bpy)

sys.path.insert(0, HERE)
import weft_import  # noqa: E402


def fail(msg):
    print(json.dumps({"ok": False, "error": msg}))
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)


def y_up_to_z_up(p):
    """weft's (x, y, z) with Y up as Blender shows it with Z up: (x, -z, y)."""
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1)


def world_positions(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    mesh = ev.to_mesh()
    try:
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
        mesh.vertices.foreach_get("co", co)
        co = co.reshape(-1, 3)
        m = np.array(ev.matrix_world, dtype=np.float64)
        return co @ m[:3, :3].T + m[:3, 3]
    finally:
        ev.to_mesh_clear()


def fresh_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    # Deliberately not any output's rate or range, so a value left unset shows.
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.frame_start, scene.frame_end = 1, 250


def run_case(case, base):
    path = os.path.join(base, case["path"])
    fresh_scene()
    before = set(o.name for o in bpy.data.objects)
    if "error" in case:
        try:
            weft_import.import_directory(path, case.get("method", "AUTO"))
        except weft_import.WeftImportError as e:
            msg = str(e)
            check(case["error"] in msg, "%s: message %r lacks %r" % (path, msg, case["error"]))
            check("\n" not in msg and "Traceback" not in msg, "%s: message not one line" % path)
            left = set(o.name for o in bpy.data.objects) - before
            check(not left, "%s: the failed import left %s" % (path, sorted(left)))
            print(json.dumps({"ok": True, "case": case["path"], "error": msg}))
            return
        fail("%s: imported, expected an error holding %r" % (path, case["error"]))

    exp = case["expect"]
    r = weft_import.import_directory(path, case.get("method", "AUTO"))
    scene = bpy.context.scene
    where = "%s (%s)" % (case["path"], case.get("method", "AUTO"))
    for key in ("method", "layout"):
        if key in exp:
            check(r[key] == exp[key], "%s: %s %r, expected %r" % (where, key, r[key], exp[key]))

    # Collection and names.
    coll = bpy.data.collections.get(exp["collection"])
    check(coll is not None and r["collection"] == exp["collection"],
          "%s: collection %r, expected %r" % (where, r["collection"], exp["collection"]))
    want = {"garment": "garment", "body": "body" if exp.get("body_vertices") else None}
    check(r["objects"] == want, "%s: objects %r, expected %r" % (where, r["objects"], want))
    names = set(o.name for o in coll.all_objects)
    for role, name in want.items():
        if name:
            check(name in names, "%s: %s is not in collection %s (%s)" % (where, name, coll.name, names))
    new = set(o.name for o in bpy.data.objects) - before
    check(new <= names, "%s: objects outside the collection: %s" % (where, sorted(new - names)))

    # Scene rate and range.
    rate = scene.render.fps / scene.render.fps_base
    check(abs(rate - exp["fps"]) <= 1e-5 * exp["fps"],
          "%s: scene rate %r (fps %d / fps_base %r), expected %r"
          % (where, rate, scene.render.fps, scene.render.fps_base, exp["fps"]))
    check(r["fps"] is not None and abs(r["fps"] - exp["fps"]) <= 1e-9 * exp["fps"],
          "%s: reported fps %r, expected %r" % (where, r["fps"], exp["fps"]))
    check((scene.frame_start, scene.frame_end) == (1, exp["frames"]),
          "%s: scene range %d..%d, expected 1..%d"
          % (where, scene.frame_start, scene.frame_end, exp["frames"]))

    # Vertex counts and positions.
    frames = np.load(os.path.join(base, exp["frames_npy"])).astype(np.float64)
    check(frames.shape[0] == exp["frames"], "%s: frames.npy has %d frames" % (where, frames.shape[0]))
    check(frames.shape[1] == exp["garment_vertices"], "%s: frames.npy vertex count" % where)
    garment = bpy.data.objects["garment"]
    n = len(garment.data.vertices)
    if exp.get("body_vertices"):
        nb = len(bpy.data.objects["body"].data.vertices)
        check(nb == exp["body_vertices"], "%s: body has %d vertices, expected %d" % (where, nb, exp["body_vertices"]))
    want_frames = y_up_to_z_up(frames)
    # Scene frame 1 + k shows frame k; consecutive frames differ by far more than the
    # tolerance, so a one-frame offset cannot pass.
    step = np.abs(np.diff(frames, axis=0)).max(axis=(1, 2))
    check(step.min() > 1e-3, "%s: consecutive frames too alike to test timing (%r)" % (where, step))
    scene.frame_set(1)
    at0 = world_positions(garment)
    if r["method"] == "GLTF":
        # Split at seams: each vertex is a copy of the template vertex it coincides with.
        check(n >= exp["garment_vertices"], "%s: garment has %d vertices" % (where, n))
        d = np.abs(at0[:, None, :] - want_frames[0][None, :, :]).max(axis=2)
        index = d.argmin(axis=1)
        check(d[np.arange(n), index].max() <= 1e-5, "%s: a glTF vertex matches no template vertex" % where)
        check(len(set(index.tolist())) == exp["garment_vertices"],
              "%s: %d template vertices found in the glTF garment, expected %d"
              % (where, len(set(index.tolist())), exp["garment_vertices"]))
    else:
        check(n == exp["garment_vertices"], "%s: garment has %d vertices, expected %d" % (where, n, exp["garment_vertices"]))
        index = np.arange(n)
    worst = []
    for k in range(exp["frames"]):
        scene.frame_set(1 + k)
        err = float(np.abs(world_positions(garment) - want_frames[k][index]).max())
        check(err <= 1e-5, "%s: at scene frame %d the garment is %.3g m from frame %d of %s"
              % (where, 1 + k, err, k, exp["frames_npy"]))
        worst.append(err)
    print(json.dumps({"ok": True, "case": case["path"], "method": r["method"], "fps": rate,
                      "frames": exp["frames"], "garment_vertices": n,
                      "max_error": max(worst), "summary": r["summary"], "notes": r["notes"]}))


def install_zip():
    """The add-on as a person installs it: a zip of the folder, installed as an extension."""
    z = os.path.join(USER_RESOURCES, "weft_import.zip")
    src = os.path.join(HERE, "weft_import")
    with zipfile.ZipFile(z, "w", zipfile.ZIP_DEFLATED) as f:
        for name in sorted(os.listdir(src)):
            if name.endswith((".py", ".toml")):
                f.write(os.path.join(src, name), "weft_import/" + name)
    fresh_scene()
    result = bpy.ops.extensions.package_install_files(
        filepath=z, repo="user_default", enable_on_install=True
    )
    check("FINISHED" in result, "installing %s: %r" % (z, result))
    module = "bl_ext.user_default.weft_import"
    check(module in bpy.context.preferences.addons, "%s is not enabled after installing" % module)
    check(hasattr(bpy.ops.import_scene, "weft"), "no import_scene.weft operator after installing")
    return sys.modules[module]


def legacy_install():
    """The folder as a legacy add-on (Blender 4.1 and older; 4.2+ still loads these):
    linked into the user's scripts/addons, found by its bl_info, enabled."""
    import addon_utils

    addons = os.path.join(bpy.utils.user_resource("SCRIPTS"), "addons")
    os.makedirs(addons, exist_ok=True)
    os.symlink(os.path.join(HERE, "weft_import"), os.path.join(addons, "weft_import"))
    found = {m.__name__: m for m in addon_utils.modules(refresh=True)}
    check("weft_import" in found, "the folder in %s is not listed as an add-on" % addons)
    info = addon_utils.module_bl_info(found["weft_import"])
    check(info["name"] == "weft output importer" and info["category"] == "Import-Export",
          "bl_info read as %r" % info)
    addon = addon_utils.enable("weft_import", default_set=True)
    check(addon is not None and hasattr(bpy.ops.import_scene, "weft"),
          "no import_scene.weft after enabling the folder")
    print(json.dumps({"ok": True, "case": "legacy add-on", "bl_info": info["name"],
                      "blender": list(info["blender"])}))
    return addon


def run_operator(op_case, base):
    addon = legacy_install()
    if bpy.app.version >= (4, 2, 0):
        import addon_utils

        addon_utils.disable("weft_import", default_set=True)
        addon = install_zip()
    # else: extensions came with Blender 4.2; the legacy add-on runs the operator.
    ok = os.path.join(base, op_case["ok"])
    result = bpy.ops.import_scene.weft(directory=ok)
    check(result == {"FINISHED"}, "operator on %s: %r" % (ok, result))
    coll = bpy.data.collections.get(os.path.basename(os.path.normpath(ok)))
    check(coll is not None and "garment" in coll.all_objects, "operator: no garment in a collection named after %s" % ok)

    def one_line_error(path, must_hold):
        before = set(o.name for o in bpy.data.objects)
        try:
            bpy.ops.import_scene.weft(directory=path)
        except RuntimeError as e:
            # Background bpy raises the operator's ERROR report as "Error: <message>".
            msg = str(e).strip()
            check(msg.startswith("Error: ") and "\n" not in msg and "Traceback" not in msg,
                  "operator on %s: not a one-line error report: %r" % (path, msg))
            check(must_hold in msg, "operator on %s: %r lacks %r" % (path, msg, must_hold))
            check(set(o.name for o in bpy.data.objects) == before, "operator on %s left objects" % path)
            return msg
        fail("operator on %s: finished, expected an error" % path)

    bad = os.path.join(base, op_case["fail"])
    msg = one_line_error(bad, os.path.abspath(bad))

    # A bug inside the add-on still reaches the UI as one line (details on the console).
    real = addon.import_directory

    def broken(*_a, **_k):
        raise ValueError("simulated internal failure")

    addon.import_directory = broken
    try:
        msg2 = one_line_error(ok, "ValueError: simulated internal failure")
    finally:
        addon.import_directory = real
    print(json.dumps({"ok": True, "case": "operator", "installed": addon.__name__,
                      "error": msg, "internal_error": msg2}))


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: test_addon.py CASES.json")
    spec_path = os.path.abspath(sys.argv[1])
    with open(spec_path) as f:
        spec = json.load(f)
    base = os.path.dirname(spec_path)
    print(json.dumps({"ok": True, "blender": bpy.app.version_string,
                      "add_on": os.path.join(HERE, "weft_import")}))
    for case in spec["cases"]:
        run_case(case, base)
    if "operator" in spec:
        run_operator(spec["operator"], base)
    print(json.dumps({"ok": True, "checked": len(spec["cases"]) + ("operator" in spec)}))


if __name__ == "__main__":
    main()
