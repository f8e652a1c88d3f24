import json
import os
import shutil
import tempfile

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ImportHelper

from ..authoring.preview import show_preview
from ..background import jobs, undo_steps
from ..toolkit import preferences, runner


class HAPTICUT_OT_import_scene(bpy.types.Operator, ImportHelper):
    """Show a scene file (.hapticut.msgpack or .hapticut.json) as a preview"""

    bl_idname = "hapticut.import_scene"
    bl_label = "Import Scene"
    # No UNDO: the preview appears later, from the job, which pushes its own step.
    bl_options = {"REGISTER"}

    filter_glob: StringProperty(default="*.hapticut.msgpack;*.hapticut.json", options={"HIDDEN"})

    def execute(self, context):
        scene = context.scene
        try:
            executable = preferences.executable(context)
        except runner.ToolkitError as error:
            self.report({"ERROR"}, str(error))
            scene.hapticut.error = str(error)
            return {"CANCELLED"}
        work = _import_steps(executable, scene.name, self.filepath)
        jobs.start(
            "Import scene", scene.name, work, on_error=jobs.shows_error_in(scene.name, "hapticut")
        )
        return {"FINISHED"}


def _import_steps(executable: str, scene_name: str, path: str):
    folder = tempfile.mkdtemp(prefix="hapticut-import-")
    preview = os.path.join(folder, "preview.npz")
    try:
        yield from runner.quick_steps(executable, "preview", path, "--out", preview)
        scene = bpy.data.scenes.get(scene_name)
        if scene is None:
            raise RuntimeError(f"the scene {scene_name!r} is gone")
        report = show_preview(scene, preview)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    settings = scene.hapticut
    settings.report_json = json.dumps(report)
    settings.status = f"imported {os.path.basename(path)}"
    settings.error = ""
    undo_steps.push("Import scene")
