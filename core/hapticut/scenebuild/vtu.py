"""The tet mesh with its materials as a VTK XML UnstructuredGrid (.vtu) for ParaView.

Written by hand (no vtk dependency): inline base64 binary arrays with a UInt32 byte-count
header, cell type 10 (VTK_TETRA), a CellData array "material" (index into the scene's
materials, listed by name in an XML comment) and "rigid" (1 where the material's model is
rigid), written atomically like scene files.
"""

from __future__ import annotations

import base64
import os
from xml.sax.saxutils import escape

import numpy as np

from ..atomic_file import write_atomically

VTK_TETRA = 10


def _binary(array: np.ndarray) -> str:
    data = np.ascontiguousarray(array).tobytes()
    header = np.array([len(data)], dtype="<u4").tobytes()
    return base64.b64encode(header + data).decode("ascii")


def _data_array(name: str, vtk_type: str, array: np.ndarray, components: int = 1) -> str:
    count = f' NumberOfComponents="{components}"' if components != 1 else ""
    return (
        f'<DataArray type="{vtk_type}" Name="{name}"{count} format="binary">'
        f"{_binary(array)}</DataArray>"
    )


def vtu_bytes(vertices, tets, tet_materials, material_names=(), rigid=None) -> bytes:
    """The .vtu document. vertices (n, 3) mm, tets (m, 4), tet_materials (m,) indices."""
    vertices = np.asarray(vertices, dtype="<f8").reshape(-1, 3)
    tets = np.asarray(tets, dtype="<i8").reshape(-1, 4)
    labels = np.asarray(tet_materials, dtype="<i4").reshape(-1)
    if len(labels) != len(tets):
        raise ValueError(f"{len(labels)} materials for {len(tets)} tets")
    offsets = np.arange(4, 4 * len(tets) + 1, 4, dtype="<i8")
    types = np.full(len(tets), VTK_TETRA, dtype="u1")
    cell_data = [_data_array("material", "Int32", labels)]
    if rigid is not None:
        cell_data.append(_data_array("rigid", "UInt8", np.asarray(rigid, dtype="u1")))
    # ParaView ignores comments; "--" may not appear inside one.
    names = ", ".join(f"{i}={n}" for i, n in enumerate(material_names)).replace("--", "- -")
    text = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt32">\n'
        f"<!-- material index: {escape(names)} -->\n"
        "<UnstructuredGrid>\n"
        f'<Piece NumberOfPoints="{len(vertices)}" NumberOfCells="{len(tets)}">\n'
        f"<Points>{_data_array('Points', 'Float64', vertices, 3)}</Points>\n"
        "<Cells>"
        f"{_data_array('connectivity', 'Int64', tets)}"
        f"{_data_array('offsets', 'Int64', offsets)}"
        f"{_data_array('types', 'UInt8', types)}"
        "</Cells>\n"
        f'<CellData Scalars="material">{"".join(cell_data)}</CellData>\n'
        "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"
    )
    return text.encode("utf-8")


def write_vtu(path: str | os.PathLike, scene) -> None:
    """Write a scene's tet mesh and materials to ``path`` atomically (temporary file, rename)."""
    rigid_models = np.array([m.model == "rigid" for m in scene.materials], dtype=bool)
    labels = np.asarray(scene.tet_materials)
    data = vtu_bytes(
        scene.vertices,
        scene.tets,
        labels,
        [m.name for m in scene.materials],
        rigid=rigid_models[labels] if len(rigid_models) else None,
    )
    write_atomically(path, data)
