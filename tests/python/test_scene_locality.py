"""The order a built scene stores its mesh in (hapticut.scenebuild.locality): a Hilbert curve
through the tets, the same mesh, and the same proxy paths as the order it came in."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hapticut import _core, engine
from hapticut.bench.blade import stroke_poses
from hapticut.scenebuild.geometry import face_pairs, tet_signed_volumes
from hapticut.scenebuild.locality import (
    hilbert_keys,
    in_locality_order,
    renumbered,
    scene_in_locality_order,
)
from hapticut.scenefile import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_hilbert_keys_visit_every_cell_of_a_grid_through_face_neighbours():
    side = 8
    cells = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    order = np.argsort(hilbert_keys(cells.astype(float), bits=3))
    steps = np.abs(np.diff(cells[order], axis=0)).sum(axis=1)
    assert len(np.unique(hilbert_keys(cells.astype(float), bits=3))) == side**3
    assert set(steps.tolist()) == {1}  # Morton order would jump; a Hilbert curve never does.


def test_hilbert_keys_of_degenerate_input():
    assert hilbert_keys(np.zeros((0, 3))).shape == (0,)
    flat = np.array([[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [2.0, 0.0, 5.0]])  # A zero-extent axis.
    assert np.all(np.diff(hilbert_keys(flat)) > 0)


def _shuffled_grid(seed: int):
    vertices, tets = _core.grid_mesh(
        list(np.linspace(0, 30, 11)), list(np.linspace(0, 20, 8)), list(np.linspace(0, 20, 8)),
        0.25, seed,
    )  # fmt: skip
    rng = np.random.default_rng(seed)
    tet_order, vertex_order = rng.permutation(len(tets)), rng.permutation(len(vertices))
    materials = rng.integers(0, 3, len(tets))
    return renumbered(vertices, tets, materials, tet_order, vertex_order)


def _shuffled_scene(scene, seed: int):
    """The scene with its tets and vertices in a random order."""
    rng = np.random.default_rng(seed)
    tet_order = rng.permutation(len(scene.tets))
    vertex_order = rng.permutation(len(scene.vertices))
    vertices, tets, tet_materials = renumbered(
        scene.vertices, scene.tets, scene.tet_materials, tet_order, vertex_order
    )
    return replace(scene, vertices=vertices, tets=tets, tet_materials=tet_materials)


def _median_neighbour_gap(tets: np.ndarray) -> float:
    pairs, _, _ = face_pairs(np.asarray(tets))
    return float(np.median(np.abs(pairs[:, 0] - pairs[:, 1])))


def test_the_order_keeps_every_tet_its_orientation_and_its_material():
    vertices, tets, materials = _shuffled_grid(4)
    new_vertices, new_tets, new_materials = in_locality_order(vertices, tets, materials)
    assert new_tets.dtype == np.int32 and new_materials.dtype == np.int32

    def described(v, t, m):  # Each tet: its corners' coordinates in order, and its material.
        return sorted(
            tuple(v[tet].ravel().tolist()) + (int(mat),) for tet, mat in zip(t, m, strict=True)
        )

    assert described(new_vertices, new_tets, new_materials) == described(vertices, tets, materials)
    assert sorted(map(tuple, new_vertices.tolist())) == sorted(map(tuple, vertices.tolist()))
    np.testing.assert_array_equal(
        np.sign(tet_signed_volumes(new_vertices, new_tets)),
        np.sign(tet_signed_volumes(vertices, tets)),
    )
    # Vertices numbered by first use: no index appears before a smaller one.
    first = np.unique(new_tets.ravel(), return_index=True)[1]
    assert np.all(np.diff(first) > 0)


def test_neighbouring_tets_end_up_near_each_other_in_memory():
    vertices, tets, materials = _shuffled_grid(5)
    before = _median_neighbour_gap(tets)
    _, new_tets, _ = in_locality_order(vertices, tets, materials)
    after = _median_neighbour_gap(new_tets)
    assert before > len(tets) / 10  # Shuffled: neighbours anywhere.
    assert after < 8, (before, after)


@pytest.mark.parametrize("coupling", ["independent", "rigid"])
@pytest.mark.parametrize("name", ["sphere80", "sphere320", "mouse", "finger"])
def test_a_reordered_example_gives_the_same_blade_stroke(name, coupling):
    """The same scene in another order is felt the same: the independent points' force along
    the bench's stroke agrees within 1e-9 N (the planes are the same up to rounding). The
    stroke is moved off the mesh's planes of symmetry: on them (the bench's own stroke through
    a sphere's centre) a point sliding over an edge finds two faces equally good, takes the
    first of the fan, and the fan's order is the tets' order. A rigid blade held by the bone
    while the device goes on through it (hundreds of N) meets its contacts in tet order; the
    rounding of its constrained fit carries from tick to tick, as a god-object's path does, so
    it agrees within 1e-4 of the peak force (measured: 1e-5 on the bunny, 0 elsewhere)."""
    scene = load_scene(EXAMPLES / f"{name}.hapticut.msgpack")
    shuffled = _shuffled_scene(scene, 6)
    forces = []
    for version in (scene, shuffled, scene_in_locality_order(shuffled)):
        space = engine.space_from_scene(version)
        poses = stroke_poses(space).copy()
        poses[:, :3] += [0.137, 0.0, 0.291]
        blade = _core.Blade(space, [-50.0, 0, 0], [50.0, 0, 0], 50, coupling=coupling)
        blade.reset(poses[0])
        forces.append(blade.run(np.ascontiguousarray(poses), 0.001)["force_N"])
    peak = np.abs(forces[0]).max()
    assert peak > 0.1  # The stroke is felt.
    atol = 1e-9 if coupling == "independent" else 1e-4 * peak
    np.testing.assert_allclose(forces[1], forces[0], rtol=0, atol=atol)
    np.testing.assert_allclose(forces[2], forces[0], rtol=0, atol=atol)


def test_convert_locality_order_writes_the_same_scene_renumbered(tmp_path):
    source = EXAMPLES / "sphere320.hapticut.msgpack"
    out = tmp_path / "sphere320.hapticut.json"
    command = ["convert", "--locality-order", str(source), str(out)]
    result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", *command],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    original, converted = load_scene(source), load_scene(out)
    assert converted.materials == original.materials and converted.blades == original.blades
    assert len(converted.tets) == len(original.tets)
    np.testing.assert_array_equal(
        np.bincount(converted.tet_materials), np.bincount(original.tet_materials)
    )
    centroids = np.asarray(converted.vertices)[np.asarray(converted.tets)].mean(axis=1)
    assert np.all(np.diff(hilbert_keys(centroids)) >= 0)
