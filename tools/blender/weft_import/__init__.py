"""weft_import: import a weft output directory into Blender in one step.

File > Import > weft output directory, or headless:

    import sys; sys.path.insert(0, "tools/blender")
    import weft_import
    result = weft_import.import_directory("sim")   # a dict; result["summary"] says it

It recognises `weft simulate --out DIR` (frames.pc2 + stats.json, obj/, scene.usda),
`weft demo`'s animation/ (garment.obj + garment.pc2 + animation.glb) and exported files
(.glb/.gltf, .usda/.usd, .pc2/.mdd beside their OBJ), imports them with Blender's own
glTF, USD or OBJ importer (with a Mesh Cache modifier for a point cache), names the
objects `garment` and `body` in a collection named after the directory, and sets the
scene's frame rate (fps / fps_base) and range 1..frames, sample 0 at frame 1.
See docs/blender.md, "The weft_import add-on".

Packaged both ways: `blender_manifest.toml` makes its zip a Blender 4.2+ extension, and
`bl_info` below lets the folder be installed as a legacy add-on (linked or copied into
scripts/addons; Blender ignores bl_info in an extension). Tested headless with bpy
4.2.23, 4.5.15 and 5.0.1 (tools/blender/test_addon.py); older Blender is not tested.
"""

bl_info = {
    "name": "weft output importer",
    "author": "weft",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > weft output directory",
    "description": "Import a weft simulate/demo/export directory: garment and body with "
    "their animation, the scene's frame rate and range",
    "category": "Import-Export",
}

import os
import traceback

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty

from .detect import METHODS, WeftImportError, plan
from .blender_import import import_directory

__all__ = ["import_directory", "plan", "WeftImportError", "METHODS", "register", "unregister"]

_FILE_EXT = (".glb", ".gltf", ".usda", ".usd", ".usdc", ".usdz", ".pc2", ".mdd")


class IMPORT_SCENE_OT_weft(bpy.types.Operator):
    """Import a weft output directory: garment and body with their animation, and the
    scene's frame rate and range"""

    bl_idname = "import_scene.weft"
    bl_label = "Import weft output"
    bl_options = {"REGISTER", "UNDO"}

    directory: StringProperty(
        name="Directory",
        description="The weft output directory (weft simulate --out, weft demo's "
        "animation/, or one holding an exported .glb, .usda or .pc2 beside its OBJ)",
        subtype="DIR_PATH",
    )
    filepath: StringProperty(
        name="File",
        description="One .glb, .gltf, .usd*, .pc2 or .mdd file to import instead of the "
        "whole directory (optional)",
        subtype="FILE_PATH",
        options={"SKIP_SAVE"},
    )
    filter_folder: BoolProperty(default=True, options={"HIDDEN"})
    filter_glob: StringProperty(
        default="*.glb;*.gltf;*.usda;*.usd;*.usdc;*.usdz;*.pc2;*.mdd;*.json;*.obj",
        options={"HIDDEN"},
    )
    method: EnumProperty(
        name="Import",
        items=(
            ("AUTO", "Automatic", "glTF if there is one, else USD, else the point cache"),
            ("GLTF", "glTF", "The .glb: garment and body as shape-key animation"),
            ("USD", "USD", "The .usda through Blender's USD importer (streamed)"),
            (
                "MESH_CACHE",
                "Point cache",
                "The rest OBJ with a Mesh Cache modifier reading the .pc2/.mdd (garment only)",
            ),
        ),
        default="AUTO",
    )
    set_scene: BoolProperty(
        name="Set Frame Rate and Range",
        description="Set the scene's frame rate to the output's and its range to 1..frames",
        default=True,
    )

    def invoke(self, context, _event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        chosen = self.filepath
        if chosen and os.path.isfile(chosen) and chosen.lower().endswith(_FILE_EXT):
            path = chosen
        else:
            path = self.directory or (os.path.dirname(chosen) if chosen else "")
        if not path:
            self.report({"ERROR"}, "weft import: choose a weft output directory")
            return {"CANCELLED"}
        try:
            result = import_directory(
                bpy.path.abspath(path), method=self.method, set_scene=self.set_scene,
                context=context,
            )
        except WeftImportError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        except Exception as e:  # a bug here, not a bad file: one line in the UI
            traceback.print_exc()  # the details go to the system console
            self.report(
                {"ERROR"},
                "weft import of %s failed: %s: %s (details in the system console)"
                % (path, type(e).__name__, e),
            )
            return {"CANCELLED"}
        for note in result["notes"]:
            self.report({"WARNING"}, note)
        self.report({"INFO"}, result["summary"])
        return {"FINISHED"}


def _menu(self, _context):
    self.layout.operator(IMPORT_SCENE_OT_weft.bl_idname, text="weft output directory")


def register():
    bpy.utils.register_class(IMPORT_SCENE_OT_weft)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    bpy.utils.unregister_class(IMPORT_SCENE_OT_weft)
