"""The preview: one object per material region (its boundary surface, from the toolkit's
preview .npz, numpy alone), coloured by material model, in a collection replaced each time."""

from __future__ import annotations

import json

import bpy
import numpy as np

from ..toolkit.units import mm_per_unit

COLLECTION = "Hapticut Preview"
# Viewport colour (RGBA) per material model.
MODEL_COLOURS = {
    "free": (0.6, 0.8, 1.0, 0.2),
    "drag": (0.85, 0.35, 0.3, 0.6),
    "viscous": (0.95, 0.8, 0.3, 0.6),
    "membrane": (0.95, 0.7, 0.6, 0.4),
    "rigid": (0.95, 0.95, 0.9, 1.0),
}
DEFAULT_COLOUR = (0.7, 0.7, 0.7, 1.0)


def read_preview(path: str) -> dict:
    """The preview's arrays and its report (a dict)."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {key: data[key] for key in data.files}
    arrays["report"] = json.loads(str(arrays.pop("report_json")))
    return arrays


def _clear(collection) -> None:
    for obj in list(collection.objects):
        mesh = obj.data
        bpy.data.objects.remove(obj)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)


def _material(name: str, model: str):
    key = f"Hapticut {name}"
    material = bpy.data.materials.get(key) or bpy.data.materials.new(key)
    material.diffuse_color = MODEL_COLOURS.get(model, DEFAULT_COLOUR)
    return material


def show_preview(scene, path: str) -> dict:
    """Replace the preview collection's objects with the preview at path; its report."""
    data = read_preview(path)
    collection = bpy.data.collections.get(COLLECTION)
    if collection is None:
        collection = bpy.data.collections.new(COLLECTION)
    if collection.name not in scene.collection.children:
        scene.collection.children.link(collection)
    # A view of the build for the viewport: its opaque surfaces would hide the scene's own
    # objects in a render.
    collection.hide_render = True
    _clear(collection)
    units = data["vertices"] / mm_per_unit(scene)
    names, models = data["material_names"], data["material_models"]
    for index in np.unique(data["face_materials"]):
        faces = data["faces"][data["face_materials"] == index]
        used, compact = np.unique(faces, return_inverse=True)
        name, model = str(names[index]), str(models[index])
        mesh = bpy.data.meshes.new(f"Hapticut {name}")
        mesh.vertices.add(len(used))
        mesh.vertices.foreach_set("co", units[used].astype(np.float32).ravel())
        mesh.loops.add(3 * len(faces))
        mesh.loops.foreach_set("vertex_index", compact.astype(np.int32).ravel())
        mesh.polygons.add(len(faces))
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(faces), 3, dtype=np.int32))
        mesh.update()
        mesh.materials.append(_material(name, model))
        obj = bpy.data.objects.new(f"Hapticut {name}", mesh)
        obj.color = MODEL_COLOURS.get(model, DEFAULT_COLOUR)
        obj["hapticut_material"] = name
        obj["hapticut_model"] = model
        collection.objects.link(obj)
    return data["report"]
