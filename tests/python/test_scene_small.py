"""Small scenes (a few hundred faces or fewer) at the builder's defaults: fTetWild's edge
length outside the sizing field stays within a share of the enclosure, the accuracy holds,
and each build's time is printed (a figure to read, never asserted)."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
from build_test_support import bunny_path
from hapticut.scenebuild import BuildError, BuildSettings, Region, build, builder, tetwild
from hapticut.scenebuild.geometry import enclosure_surface
from hapticut.scenebuild.repair import read_surface
from hapticut.scenefile import Material

SOFT = Material("soft_tissue", "drag", drag_distance_mm=1.0)
# fTetWild's output differs between runs: each small scene is built this often.
BUILDS = 3


def cube_region(side_mm: float) -> Region:
    """The scripting docs' cube (docs/addon.md): 12 triangles, centred on the origin."""
    half = np.full(3, side_mm / 2)
    return Region("cube", *enclosure_surface("box", -half, half, 0.0), SOFT)


def small_scan(faces: int, length_mm: float) -> Region:
    """pymeshlab's sample bunny, holes closed and decimated to ``faces``, ``length_mm`` long."""
    import pymeshlab

    vertices, triangles = read_surface(bunny_path())
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=triangles))
    meshes.meshing_remove_duplicate_vertices()
    meshes.meshing_close_holes(maxholesize=200, newfaceselected=False)
    meshes.meshing_decimation_quadric_edge_collapse(targetfacenum=faces, preservetopology=True)
    mesh = meshes.current_mesh()
    vertices, triangles = mesh.vertex_matrix(), mesh.face_matrix()
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    vertices = (vertices - (low + high) / 2) * (length_mm / float((high - low).max()))
    return Region("bunny", vertices, triangles, SOFT)


def edge_length_handed_to_tetwild(
    monkeypatch, region: Region, settings: BuildSettings
) -> tuple[float, float]:
    """The edge length the build hands fTetWild and the enclosure's largest side (the build
    stops there)."""
    handed = []

    def stop_at_tetwild(vertices, faces, params, sizing=None, *, poll=None):
        handed.append((params.edge_length_mm, float(np.ptp(vertices, axis=0).max())))
        raise RuntimeError("stopped before fTetWild")

    monkeypatch.setattr(tetwild, "tetrahedralize", stop_at_tetwild)
    with pytest.raises(BuildError, match="stopped before fTetWild"):
        build([region], settings=settings)
    return handed[0]


def test_ftetwild_edge_length_stays_within_a_share_of_the_enclosure(monkeypatch):
    # The cube's own edges make its far edges (and the air's, three times them) longer than
    # the enclosure: fTetWild gets the capped length.
    edge, side = edge_length_handed_to_tetwild(monkeypatch, cube_region(10.0), BuildSettings())
    assert edge == pytest.approx(builder.OUTER_EDGE_SHARE * side)
    # Far edges well inside the cap reach fTetWild as they are (the air's: 3x edge_far_mm).
    settings = BuildSettings(margin_mm=20.0, edge_near_mm=1.0, edge_far_mm=2.0)
    edge, side = edge_length_handed_to_tetwild(monkeypatch, cube_region(10.0), settings)
    assert edge == pytest.approx(builder.AIR_FAR_RATIO * 2.0)
    assert edge < builder.OUTER_EDGE_SHARE * side


def built_within_the_accuracy(region: Region, settings: BuildSettings, label: str) -> None:
    """Build BUILDS times; each holds the accuracy and labels the region. Prints the times."""
    seconds = []
    for _ in range(BUILDS):
        start = time.perf_counter()
        scene = build([region], settings=replace(settings, in_subprocess=True))
        seconds.append(time.perf_counter() - start)
        report = scene.metadata["build_report"]
        assert report["accuracy_not_held"] == []
        assert report["deviation_mm"][region.name] <= report["settings"]["accuracy_mm"]
        assert report["tets_per_region"][region.name] > 0
        assert report["tets_per_region"]["(air)"] > 0
    print(
        f"{label}: {len(region.faces)} faces, build {np.median(seconds):.2f} s median "
        f"({min(seconds):.2f} to {max(seconds):.2f} s over {BUILDS} builds)"
    )


def test_the_scripting_cube_builds_within_the_accuracy():
    settings = BuildSettings(accuracy_mm=1.0, edge_near_mm=5.0)  # The scripting docs' settings.
    built_within_the_accuracy(cube_region(10.0), settings, "10 mm cube, scripting docs")


def test_the_10_mm_cube_builds_at_its_defaults_within_the_accuracy():
    built_within_the_accuracy(cube_region(10.0), BuildSettings(), "10 mm cube, defaults")


def test_a_small_scan_builds_at_its_defaults_within_the_accuracy():
    region = small_scan(900, 100.0)
    assert len(region.faces) < 1000
    built_within_the_accuracy(region, BuildSettings(), "100 mm bunny, defaults")
