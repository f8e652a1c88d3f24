"""What the add-on stores in a .blend: per object (role, material, blade) and per scene
(build settings, the last build's report and problems)."""

from __future__ import annotations

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from ..toolkit import materials

# A path property that may start with "//" (relative to the .blend) says so from Blender 5.0
# on, which warns otherwise; Blender 4.2 has no such option and takes "//" everywhere.
BLEND_RELATIVE = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (5, 0, 0) else set()

ROLES = (
    ("NONE", "None", "Not part of the scene"),
    ("REGION", "Region", "A closed mesh filled with one material"),
    ("BLADE", "Blade", "A blade: its cutting edge samples the material"),
)
EDGE_MODES = (
    ("VERTICES", "Two vertices", "The edge between two vertices picked in edit mode"),
    ("AXIS", "Axis", "A segment along a local axis, centred on the origin"),
)
AXES = (("X", "X", ""), ("Y", "Y", ""), ("Z", "Z", ""))
# A blade's coupling and orientation, as the scene file names them in lower case
# (docs/scene-format.md, "Blades").
COUPLINGS = (
    ("RIGID", "Rigid", "One knife: the whole edge stops at rigid material; renders points x k"),
    ("INDEPENDENT", "Independent points", "The paper's blade: each point on its own"),
)
ORIENTATIONS = (
    ("FREE", "Free", "A rigid blade turns where it is held (a bone under one end tilts it)"),
    ("LOCKED", "Locked", "A rigid blade keeps the device's orientation (no torque rendered)"),
)
CUSTOM = "custom"
# What a region's material becomes where a blade has cut it (the request's "cut"; the scene
# file's cut_to, docs/scene-format.md). Only materials a blade cuts take one.
CUT_CHOICES = (
    ("UNCHANGED", "Stays as it is", "A cut tet stays as it was: cutting it again costs as much"),
    ("FREE", "Free", "Cut tissue offers no resistance, as air"),
    (
        "WEAKER",
        "Weaker",
        "The same model, its parameters times Factor: a drag's distance, a viscous "
        "material's viscosity and lag cap, a membrane's break force",
    ),
)


def _preset_names(self, context, edit_text):
    table = materials.cached_material_table()
    names = [p["name"] for p in table["presets"]] if table else []
    return [*names, CUSTOM]


def _model_names(self, context, edit_text):
    table = materials.cached_material_table()
    return [m["name"] for m in table["models"]] if table else []


class HAPTICUT_PG_parameter(bpy.types.PropertyGroup):
    """One parameter of a custom material (its range is the material table's)."""

    value: FloatProperty(name="Value")


class HAPTICUT_PG_object(bpy.types.PropertyGroup):
    role: EnumProperty(name="Role", items=ROLES, default="NONE")
    # Region.
    material_preset: StringProperty(
        name="Material",
        description="A preset of the toolkit's material table, or 'custom'",
        default="soft_tissue",
        search=_preset_names,
    )
    custom_name: StringProperty(
        name="Material name", description="Regions with one name share one material"
    )
    custom_model: StringProperty(name="Model", search=_model_names, default="drag")
    custom_parameters: CollectionProperty(type=HAPTICUT_PG_parameter)
    cut_becomes: EnumProperty(
        name="Once cut",
        description="What the material becomes where a blade has cut it",
        items=CUT_CHOICES,
        default="UNCHANGED",
    )
    cut_factor: FloatProperty(
        name="Factor",
        description="What a cut tet keeps of the material's parameters (0.1: a tenth of its "
        "drag); above 0, at most 1",
        default=0.1,
        min=0.0,
        max=1.0,
        subtype="FACTOR",
    )
    # Blade.
    blade_points: IntProperty(name="Points", default=50, min=2, max=1000)
    blade_coupling: EnumProperty(name="Coupling", items=COUPLINGS, default="RIGID")
    blade_orientation: EnumProperty(name="Orientation", items=ORIENTATIONS, default="FREE")
    edge_mode: EnumProperty(name="Cutting edge", items=EDGE_MODES, default="VERTICES")
    edge_vertex_a: IntProperty(name="Edge start vertex", default=-1, min=-1)
    edge_vertex_b: IntProperty(name="Edge end vertex", default=-1, min=-1)
    edge_axis: EnumProperty(name="Axis", items=AXES, default="X")
    edge_length: FloatProperty(
        name="Length", default=0.0, min=0.0, subtype="DISTANCE", unit="LENGTH"
    )
    device: StringProperty(
        name="Device", description="The servo device that moves this blade", default="sim"
    )


class HAPTICUT_PG_problem(bpy.types.PropertyGroup):
    object_name: StringProperty(name="Object")
    problem: StringProperty(name="Problem")
    place: StringProperty(name="Place")  # Where on the object (mesh_places), or "".
    remedy: StringProperty(name="Remedy")  # What to do (problem_remedies), or "".


class HAPTICUT_PG_scene(bpy.types.PropertyGroup):
    accuracy: FloatProperty(
        name="Accuracy",
        description="How far the meshed surfaces may lie from yours (0: 1% of the size). "
        "Tighter keeps thinner features and costs more tets",
        default=0.0,
        min=0.0,
        subtype="DISTANCE",
        unit="LENGTH",
    )
    edge_near: FloatProperty(
        name="Edge near",
        description="Tet edge length at the surfaces (0: their mean edge). Half of it gives "
        "about 4-8x the tets and the build time",
        default=0.0,
        min=0.0,
        subtype="DISTANCE",
        unit="LENGTH",
    )
    edge_far: FloatProperty(
        name="Edge far",
        description="Tet edge length far from the surfaces, mostly air (0: 4x near). Larger "
        "is cheaper",
        default=0.0,
        min=0.0,
        subtype="DISTANCE",
        unit="LENGTH",
    )
    enclosure: EnumProperty(
        name="Enclosure",
        items=(
            ("box", "Box", "A tight box"),
            ("cube", "Cube", "A cube (the paper's)"),
            ("tetrahedron", "Tetrahedron", "4 boundary faces"),
        ),
        default="box",
    )
    # On, as the toolkit's builder: the air is most of what coarsening removes.
    coarsen: BoolProperty(
        name="Coarsen", description="Fewer tets (most of them air), a slower build", default=True
    )
    work_directory: StringProperty(
        name="Work directory",
        subtype="DIR_PATH",
        options=BLEND_RELATIVE,
        description="Where builds go; // is the .blend's folder (empty: a folder of this "
        "file's own in the user's data folder, forked by Save As)",
    )
    # Names the scene's folder in the user's data folder (work_folder.py): kept by the .blend,
    # a new one when Save As forks the folder (file_handlers.py).
    work_id: StringProperty(name="Work folder id")
    # The last build (kept in the .blend).
    build_hash: StringProperty(name="Build hash")
    report_json: StringProperty(name="Report")
    status: StringProperty(name="Status")
    error: StringProperty(name="Error")
    problems: CollectionProperty(type=HAPTICUT_PG_problem)
    # The running build (drawn as a progress bar).
    running: BoolProperty(name="Running", default=False)
    progress: FloatProperty(name="Progress", min=0.0, max=1.0, subtype="FACTOR")
    stage: StringProperty(name="Stage")
    active_index: IntProperty(name="Active")


classes = (HAPTICUT_PG_parameter, HAPTICUT_PG_object, HAPTICUT_PG_problem, HAPTICUT_PG_scene)


def attach() -> None:
    bpy.types.Object.hapticut = PointerProperty(type=HAPTICUT_PG_object)
    bpy.types.Scene.hapticut = PointerProperty(type=HAPTICUT_PG_scene)


def detach() -> None:
    del bpy.types.Scene.hapticut
    del bpy.types.Object.hapticut
