"""What Tetrahedralize and Check Scene share as operators: started from the UI, they stay
modal only to let Esc cancel the scene's job (the timer follows it)."""

from __future__ import annotations

from . import build_job, building


class CancelsJobOnEsc:
    """Mixin for an operator whose execute() starts the scene's job (build_job)."""

    def invoke(self, context, event):
        result = self.execute(context)
        if "FINISHED" in result and build_job.running(context.scene.name):
            self._scene_name = context.scene.name
            context.window_manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}
        return result

    def modal(self, context, event):
        job = build_job.running(self._scene_name)
        if job is None:
            return {"FINISHED"}
        if event.type == "ESC" and event.value == "PRESS":
            building.cancel_build(self._scene_name)
            self.report({"WARNING"}, f"{job.kind} cancelled")
            return {"CANCELLED"}
        return {"PASS_THROUGH"}
