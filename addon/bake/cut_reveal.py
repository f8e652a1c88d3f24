"""The Geometry Nodes group that reveals a cut surface over time: a face shows from the frame
it was cut at (its integer face attribute ``hapticut_cut_frame``) on."""

from __future__ import annotations

import bpy

GROUP_NAME = "Hapticut Cut Reveal"
FRAME_ATTRIBUTE = "hapticut_cut_frame"


def reveal_group():
    group = bpy.data.node_groups.get(GROUP_NAME)
    if group is not None:
        return group
    group = bpy.data.node_groups.new(GROUP_NAME, "GeometryNodeTree")
    group.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    group.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = group.nodes, group.links
    given = nodes.new("NodeGroupInput")
    result = nodes.new("NodeGroupOutput")
    attribute = nodes.new("GeometryNodeInputNamedAttribute")
    attribute.data_type = "INT"
    attribute.inputs["Name"].default_value = FRAME_ATTRIBUTE
    time = nodes.new("GeometryNodeInputSceneTime")
    later = nodes.new("FunctionNodeCompare")
    later.data_type = "FLOAT"
    later.operation = "GREATER_THAN"
    delete = nodes.new("GeometryNodeDeleteGeometry")
    delete.domain = "FACE"
    links.new(attribute.outputs["Attribute"], later.inputs[0])
    links.new(time.outputs["Frame"], later.inputs[1])
    links.new(given.outputs[0], delete.inputs["Geometry"])
    links.new(later.outputs["Result"], delete.inputs["Selection"])
    links.new(delete.outputs["Geometry"], result.inputs[0])
    for x, node in enumerate((given, attribute, time, later, delete, result)):
        node.location = (200 * x, 0)
    return group


def add_reveal(obj):
    modifier = obj.modifiers.new("Hapticut Reveal", "NODES")
    modifier.node_group = reveal_group()
    return modifier
