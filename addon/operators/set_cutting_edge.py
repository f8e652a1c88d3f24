import bmesh
import bpy


class HAPTICUT_OT_set_cutting_edge(bpy.types.Operator):
    """Make the two selected vertices the blade's cutting edge (in edit mode)"""

    bl_idname = "hapticut.set_cutting_edge"
    bl_label = "Set Cutting Edge"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.object
        return obj is not None and obj.type == "MESH" and obj.hapticut.role == "BLADE"

    def execute(self, context):
        obj = context.object
        if obj.mode == "EDIT":
            mesh = bmesh.from_edit_mesh(obj.data)
            selected = [v.index for v in mesh.verts if v.select]
        else:
            selected = [v.index for v in obj.data.vertices if v.select]
        if len(selected) != 2:
            self.report({"ERROR"}, f"{obj.name}: select exactly two vertices (not {len(selected)})")
            return {"CANCELLED"}
        settings = obj.hapticut
        settings.edge_mode = "VERTICES"
        settings.edge_vertex_a, settings.edge_vertex_b = selected
        return {"FINISHED"}
