"""The checks of "mesh" in a scene tree, vectorized with numpy for big meshes.

Each check has a fast path for the usual case (rows that are lists of plain numbers), tested
with set(map(type, ...)) at C speed, and otherwise falls back to element-by-element checks that
name the first offending element. Both paths, and core/src/scene_io.cpp, report the same first
error: the passes run in the same order and each scans in document order.
"""

from __future__ import annotations

from itertools import chain
from typing import Any

import numpy as np

from .tree_values import (
    ARRAY_TYPES,
    child,
    dump_number,
    expect_array,
    fail,
    read_integer,
    read_point,
)

# A tet whose |6 V| is below this fraction of (longest edge)^3 has no volume (as TetMesh).
ZERO_VOLUME_RATIO = 1e-12
TET_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
_NUMBER_TYPES = {int, float}
_INTEGER_TYPES = {int}


def _is_plain_table(rows: list, width: int, element_types: set[type]) -> bool:
    """True when every row is a list of ``width`` values whose types are in element_types."""
    return (
        set(map(type, rows)) <= set(ARRAY_TYPES)
        and set(map(len, rows)) <= {width}
        and set(map(type, chain.from_iterable(rows))) <= element_types
    )


def _first_true(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(mask)), mask.shape))


def read_vertices(rows: Any, pointer: str) -> np.ndarray:
    """(n, 3) float64 from a list of [x, y, z] finite numbers."""
    expect_array(rows, pointer)
    if _is_plain_table(rows, 3, _NUMBER_TYPES):
        try:
            vertices = np.array(rows, dtype=np.float64).reshape(len(rows), 3)
        except OverflowError:  # An integer beyond the double range: named below.
            vertices = None
        if vertices is not None:
            finite = np.isfinite(vertices)
            if finite.all():
                return vertices
            row, column = _first_true(~finite)
            fail(child(child(pointer, row), column), "not a finite number")
    points = [read_point(row, child(pointer, i)) for i, row in enumerate(rows)]
    return np.array(points, dtype=np.float64).reshape(len(rows), 3)


def read_tet_indices(rows: Any, pointer: str, vertex_count: int) -> np.ndarray:
    """(m, 4) int64 vertex indices, each in range; at least one tet."""
    expect_array(rows, pointer)
    if not rows:
        fail(pointer, "no tets (a scene needs at least one)")
    if _is_plain_table(rows, 4, _INTEGER_TYPES):
        try:
            tets = np.array(rows, dtype=np.int64).reshape(len(rows), 4)
        except OverflowError:
            tets = None
        if tets is not None:
            out_of_range = (tets < 0) | (tets >= vertex_count)
            if not out_of_range.any():
                return tets
            row, column = _first_true(out_of_range)
            _fail_index(child(child(pointer, row), column), int(tets[row, column]), vertex_count)
    return _read_tet_indices_one_by_one(rows, pointer, vertex_count)


def _read_tet_indices_one_by_one(rows: list, pointer: str, vertex_count: int) -> np.ndarray:
    tets = np.empty((len(rows), 4), dtype=np.int64)
    for t, row in enumerate(rows):
        tet_pointer = child(pointer, t)
        expect_array(row, tet_pointer)
        if len(row) != 4:
            fail(tet_pointer, f"expected 4 vertex indices, got {len(row)}")
        for k, value in enumerate(row):
            index_pointer = child(tet_pointer, k)
            index = read_integer(value, index_pointer)
            if not 0 <= index < vertex_count:
                _fail_index(index_pointer, value, vertex_count)
            tets[t, k] = index
    return tets


def _fail_index(pointer: str, value: int | float, vertex_count: int) -> None:
    fail(pointer, f"vertex index {dump_number(value)} out of range ({vertex_count} vertices)")


def check_distinct_vertices(tets: np.ndarray, pointer: str) -> None:
    ordered = np.sort(tets, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
    if not repeated.any():
        return
    t = int(np.argmax(repeated))
    tet = tets[t].tolist()
    k = next(k for k in range(1, 4) if tet[k] in tet[:k])
    fail(child(pointer, t), f"repeated vertex index {tet[k]}")


def signed_volumes6(vertices: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """6 x the signed volume of every tet and its longest edge.

    Operation for operation the arithmetic of TetMesh and scene_io.cpp (dot, cross and norm of
    vec3.h, evaluated left to right), so all three classify the same tets as flat.
    """
    # Huge finite coordinates overflow to inf or NaN here exactly as in C++, where the volume
    # test then says "zero volume"; numpy's warnings about it say nothing new.
    with np.errstate(over="ignore", invalid="ignore"):
        a, b, c, d = (vertices[tets[:, k]] for k in range(4))
        e1, e2, e3 = b - a, c - a, d - a
        cross_x = e2[:, 1] * e3[:, 2] - e2[:, 2] * e3[:, 1]
        cross_y = e2[:, 2] * e3[:, 0] - e2[:, 0] * e3[:, 2]
        cross_z = e2[:, 0] * e3[:, 1] - e2[:, 1] * e3[:, 0]
        det = e1[:, 0] * cross_x + e1[:, 1] * cross_y + e1[:, 2] * cross_z
        volume6 = 6.0 * (det / 6.0)
        corners = (a, b, c, d)
        longest = np.zeros(len(tets))
        for i, j in TET_EDGES:
            edge = corners[i] - corners[j]
            length = np.sqrt(
                edge[:, 0] * edge[:, 0] + edge[:, 1] * edge[:, 1] + edge[:, 2] * edge[:, 2]
            )
            longest = np.maximum(longest, length)
    return volume6, longest


def check_volumes(
    vertices: np.ndarray, tets: np.ndarray, pointer: str, strict: bool
) -> tuple[np.ndarray, int]:
    """Rejects flat tets (and inverted ones when strict); re-orients inverted ones otherwise.

    Returns the tets (re-oriented by swapping their last two vertices) and how many flipped.
    """
    volume6, longest = signed_volumes6(vertices, tets)
    flat = ~(np.abs(volume6) > ZERO_VOLUME_RATIO * longest * longest * longest)
    inverted = volume6 < 0.0
    bad = flat | inverted if strict else flat
    if bad.any():
        t = int(np.argmax(bad))
        fail(child(pointer, t), "zero volume" if flat[t] else "inverted (negative volume)")
    tets = tets.copy()
    tets[inverted, 2], tets[inverted, 3] = tets[inverted, 3], tets[inverted, 2]
    return tets, int(inverted.sum())


def read_tet_materials(rows: Any, pointer: str, tet_count: int, material_count: int) -> np.ndarray:
    """(m,) int64 material indices, one per tet, each naming an entry of "materials"."""
    expect_array(rows, pointer)
    if len(rows) != tet_count:
        fail(pointer, f"{len(rows)} entries for {tet_count} tets")
    if set(map(type, rows)) <= _INTEGER_TYPES:
        try:
            indices = np.array(rows, dtype=np.int64).reshape(len(rows))
        except OverflowError:
            indices = None
        if indices is not None:
            unknown = (indices < 0) | (indices >= material_count)
            if not unknown.any():
                return indices
            (t,) = _first_true(unknown)
            _fail_material(child(pointer, t), int(indices[t]), material_count)
    indices = np.empty(len(rows), dtype=np.int64)
    for t, value in enumerate(rows):
        index = read_integer(value, child(pointer, t))
        if not 0 <= index < material_count:
            _fail_material(child(pointer, t), value, material_count)
        indices[t] = index
    return indices


def _fail_material(pointer: str, value: int | float, material_count: int) -> None:
    fail(pointer, f"unknown material {dump_number(value)} ({material_count} materials)")
