"""The .vtu export: a VTK XML UnstructuredGrid that reads back to the same mesh and labels."""

from __future__ import annotations

import base64
import xml.etree.ElementTree as ET

import numpy as np
from hapticut.scenebuild.vtu import write_vtu
from hapticut.scenefile import Material, Scene

DTYPES = {"Float64": "<f8", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


def read_arrays(path) -> dict[str, np.ndarray]:
    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid" and root.get("header_type") == "UInt32"
    arrays = {}
    for element in root.iter("DataArray"):
        raw = base64.b64decode(element.text)
        size = int(np.frombuffer(raw[:4], "<u4")[0])
        assert size == len(raw) - 4
        arrays[element.get("Name")] = np.frombuffer(raw[4:], DTYPES[element.get("type")])
    piece = root.find("UnstructuredGrid/Piece")
    arrays["_counts"] = (int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells")))
    return arrays


def test_vtu_holds_points_tets_and_materials(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], np.int32)
    scene = Scene(
        materials=[Material("air", "free"), Material("bone", "rigid")],
        vertices=vertices,
        tets=tets,
        tet_materials=np.array([0, 1], np.int32),
    )
    path = tmp_path / "two.vtu"
    write_vtu(path, scene)
    arrays = read_arrays(path)
    assert arrays["_counts"] == (5, 2)
    np.testing.assert_array_equal(arrays["Points"].reshape(-1, 3), vertices)
    np.testing.assert_array_equal(arrays["connectivity"].reshape(-1, 4), tets)
    np.testing.assert_array_equal(arrays["offsets"], [4, 8])
    np.testing.assert_array_equal(arrays["types"], [10, 10])  # VTK_TETRA
    np.testing.assert_array_equal(arrays["material"], [0, 1])
    np.testing.assert_array_equal(arrays["rigid"], [0, 1])
    assert "0=air, 1=bone" in path.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["two.vtu"]  # no temporary left
