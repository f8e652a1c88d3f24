"""The sidebar tab *Hapticut*: the scene's regions and blades, checks, build, report."""

from __future__ import annotations

import json

import bpy

from ..authoring import build_job, work_folder
from ..authoring.report_text import cost_lines, report_lines, warnings
from ..toolkit import materials
from .sidebar import (
    SidebarPanel,
    SidebarSubpanel,
    draw_properties,
    draw_status,
    draw_wrapped,
)


def draw_job(layout, settings, job: build_job.Job | None) -> None:
    """The running build or check: its progress bar and its cancel button (the scene's own
    progress properties when the job is not at hand, as after reloading add-ons)."""
    if job is None:
        text, kind = f"{settings.stage} {100 * settings.progress:.0f}%", "build"
    else:
        text, kind = build_job.progress_text(job), job.kind
    layout.progress(factor=settings.progress, type="BAR", text=text)
    layout.operator("hapticut.cancel_build", icon="CANCEL", text=f"Cancel {kind.title()}")


def draw_cut(layout, settings, model: dict | None, parameters: dict) -> None:
    """*Once cut* for a material a blade cuts (and a weaker copy's parameters), else why there
    is nothing to set."""
    if model is None:
        return
    if not materials.cuttable(model):
        layout.label(text=f"Once cut: a blade never cuts {model['name']} material", icon="INFO")
        return
    layout.prop(settings, "cut_becomes")
    if settings.cut_becomes == "WEAKER":
        layout.prop(settings, "cut_factor")
        factor = settings.cut_factor
        values = [(p["name"], parameters.get(p["name"], p["default"])) for p in model["parameters"]]
        layout.label(
            text=f"once cut: {model['name']}: "
            + ", ".join(f"{name} {factor * value:g}" for name, value in values)
        )


class HAPTICUT_UL_objects(bpy.types.UIList):
    """Regions and blades, with their materials or edges."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_property):
        settings = item.hapticut
        if settings.role == "REGION":
            preset = settings.material_preset
            text = settings.custom_name or item.name if preset == "custom" else preset
            layout.label(text=item.name, icon="MESH_DATA")
            layout.label(text=text)
        else:
            layout.label(text=item.name, icon="SCULPTMODE_HLT")
            layout.label(text=f"blade, {settings.blade_points} points")

    def filter_items(self, context, data, propname):
        objects = getattr(data, propname)
        flags = [self.bitflag_filter_item if o.hapticut.role != "NONE" else 0 for o in objects]
        return flags, []


class HAPTICUT_PT_scene(SidebarPanel, bpy.types.Panel):
    bl_label = "Hapticut"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        settings = scene.hapticut
        layout.template_list("HAPTICUT_UL_objects", "", scene, "objects", settings, "active_index")
        for problem in settings.problems:
            text = (
                f"{problem.object_name}: {problem.problem}"
                if problem.object_name
                else problem.problem
            )
            draw_wrapped(layout, context, text, icon="ERROR")
            if problem.place:
                draw_wrapped(layout, context, problem.place, icon="ORIENTATION_LOCAL")
            if problem.remedy:
                draw_wrapped(layout, context, f"To fix: {problem.remedy}", icon="TOOL_SETTINGS")
        job = build_job.running(scene.name)
        if job is not None and job.kind == "check":
            draw_job(layout, settings, job)
        else:
            layout.operator("hapticut.check_scene", icon="CHECKMARK")


class HAPTICUT_PT_object(SidebarSubpanel, bpy.types.Panel):
    bl_label = "Object"

    @classmethod
    def poll(cls, context):
        return context.object is not None

    def draw(self, context):
        layout = self.layout
        obj = context.object
        settings = obj.hapticut
        layout.prop(settings, "role")
        if settings.role == "REGION":
            self.draw_region(layout, settings)
        elif settings.role == "BLADE":
            layout.prop(settings, "blade_points")
            layout.prop(settings, "blade_coupling")
            if settings.blade_coupling == "RIGID":
                layout.prop(settings, "blade_orientation")
            layout.prop(settings, "edge_mode")
            if settings.edge_mode == "VERTICES":
                row = layout.row()
                row.label(text=f"vertices {settings.edge_vertex_a}, {settings.edge_vertex_b}")
                row.operator("hapticut.set_cutting_edge")
            else:
                layout.prop(settings, "edge_axis")
                layout.prop(settings, "edge_length")
            layout.prop(settings, "device")

    def draw_region(self, layout, settings):
        layout.prop(settings, "material_preset")
        table = materials.cached_material_table()
        if table is None:
            layout.label(text="Material table not read: Check in the preferences", icon="INFO")
            return
        if settings.material_preset != "custom":
            preset = materials.preset(table, settings.material_preset)
            if preset is not None:
                layout.label(
                    text=f"{preset['model']}: "
                    + ", ".join(f"{k} {v:g}" for k, v in preset["parameters"].items())
                )
            layout.operator("hapticut.set_custom_material")
            if preset is not None:
                model = materials.model(table, preset["model"])
                draw_cut(layout, settings, model, preset["parameters"])
            return
        layout.prop(settings, "custom_name")
        layout.prop(settings, "custom_model")
        model = materials.model(table, settings.custom_model)
        ranges = {p["name"]: p for p in model["parameters"]} if model else {}
        for item in settings.custom_parameters:
            row = layout.row()
            row.prop(item, "value", text=item.name)
            limits = ranges.get(item.name)
            if limits:
                row.label(text=materials.range_text(limits))
        parameters = {item.name: item.value for item in settings.custom_parameters}
        draw_cut(layout, settings, model, parameters)


class HAPTICUT_PT_build(SidebarSubpanel, bpy.types.Panel):
    bl_label = "Build"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hapticut
        draw_properties(
            layout,
            settings,
            ("accuracy", "edge_near", "edge_far", "enclosure", "coarsen", "work_directory"),
        )
        costs = layout.column(align=True)
        costs.scale_y = 0.8
        report = json.loads(settings.report_json) if settings.report_json else {}
        for line in cost_lines(report):
            costs.label(text=line)
        if settings.running:
            draw_job(layout, settings, build_job.running(context.scene.name))
        else:
            layout.operator("hapticut.tetrahedralize", icon="MESH_ICOSPHERE")
        draw_status(layout, settings.status, settings.error)
        for warning, remedy in warnings(report):  # The build's, where they are seen.
            draw_wrapped(layout, context, warning, icon="ERROR")
            if remedy:
                draw_wrapped(layout, context, f"To fix: {remedy}", icon="TOOL_SETTINGS")
        if work_folder.shared_with(context.scene) is not None:
            layout.operator("hapticut.fork_work_folder", icon="DUPLICATE")
        row = layout.row()
        row.operator("hapticut.export_scene", icon="EXPORT")
        row.operator("hapticut.import_scene", icon="IMPORT")


class HAPTICUT_PT_report(SidebarSubpanel, bpy.types.Panel):
    bl_label = "Report"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return bool(context.scene.hapticut.report_json)

    def draw(self, context):
        report = json.loads(context.scene.hapticut.report_json)
        for line in report_lines(report):
            self.layout.label(text=line)


classes = (
    HAPTICUT_UL_objects,
    HAPTICUT_PT_scene,
    HAPTICUT_PT_object,
    HAPTICUT_PT_build,
    HAPTICUT_PT_report,
)
