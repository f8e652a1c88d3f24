"""What the user can do about each problem the checks and the build report: the remedy, with
the Blender command (menu path and operator) where there is one. No bpy.

The problems are the toolkit's words (hapticut.build_request.input_problems,
hapticut.scenebuild.check_layout) and the add-on's own; a problem none of these patterns
knows gets no remedy rather than a wrong one.
"""

from __future__ import annotations

VOXEL_REMESH = (
    "a voxel Remesh rebuilds it closed and clean (Object Data Properties > Remesh > Voxel "
    "Remesh, bpy.ops.object.voxel_remesh(); or a Remesh modifier in Voxel mode)"
)

# (words the problem holds, what to do), first match wins.
REMEDIES = (
    (
        "intersects itself",
        f"{VOXEL_REMESH}; or in Edit Mode, Select > Select All by Trait > Interior Faces and "
        "Face > Intersect (Knife) to find and cut the crossing faces",
    ),
    (
        "the mesh is open",
        "close the holes: in Edit Mode, Select > Select All by Trait > Non Manifold shows "
        f"them, Face > Fill (F, bpy.ops.mesh.fill()) closes one; or {VOXEL_REMESH}",
    ),
    (
        "not manifold",
        "in Edit Mode, Select > Select All by Trait > Non Manifold shows the edges; Mesh > "
        "Clean Up > Merge by Distance (bpy.ops.mesh.remove_doubles()) joins doubled vertices; "
        f"or {VOXEL_REMESH}",
    ),
    (
        "has no volume",
        "a region is a closed volume: give a sheet thickness with a Solidify modifier",
    ),
    (
        "closed parts touch",
        "parts of one region must be apart or one surface: move them apart, join them into "
        f"one closed surface ({VOXEL_REMESH}), or make each its own region (Edit Mode, Mesh "
        "> Separate > By Loose Parts, bpy.ops.mesh.separate(type='LOOSE'))",
    ),
    (
        "crosses region",
        "regions must be nested or apart: move or shrink one of the two, or cut one out of "
        "the other (a Boolean modifier, Difference)",
    ),
    (
        "comes within",
        "move the two regions apart, or lower the scene's Accuracy (the Build panel) so the "
        "layer between them is resolved",
    ),
    (
        "mesh files have no units",
        "check the scene's Unit Scale (Scene Properties > Units; 1 Blender unit is Unit "
        "Scale metres) and the object's scale",
    ),
)


def remedy(problem: str) -> str:
    """The remedy for problem ("" when none is known)."""
    return next((fix for words, fix in REMEDIES if words in problem), "")
