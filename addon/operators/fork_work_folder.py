import bpy

from ..authoring import build_job, work_folder


class HAPTICUT_OT_fork_work_folder(bpy.types.Operator):
    """Give this scene a work folder of its own (a new id; its build shared into it, its last
    recording copied), so this file and the one it was copied from never write into one"""

    bl_idname = "hapticut.fork_work_folder"
    bl_label = "Fork Work Folder"
    # No UNDO: the new folder is on disk; an undo would bring back the shared id, which the
    # next build or stroke would fork again.
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and build_job.running(context.scene.name) is None

    def execute(self, context):
        scene = context.scene
        other = work_folder.shared_with(scene)
        work = work_folder.fork(scene, bpy.data.filepath)
        work_folder.settle_after_load(scene)
        whose = f" (it was also {other}'s)" if other else ""
        self.report({"INFO"}, f"this scene's work folder is now {work}{whose}")
        return {"FINISHED"}
