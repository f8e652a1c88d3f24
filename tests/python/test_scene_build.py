"""hapticut.scenebuild.build on small meshes: labels, enclosures, sizing, progress, report."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from build_test_support import bunny_path, icosphere, materials_at
from hapticut.scenebuild import (
    BuildCancelled,
    BuildError,
    BuildSettings,
    RefineZone,
    Region,
    build,
    builder,
)
from hapticut.scenebuild.geometry import (
    boundary_faces,
    enclosure_planes,
    enclosure_surface,
    winding_numbers,
)
from hapticut.scenebuild.locality import hilbert_keys
from hapticut.scenebuild.repair import read_surface
from hapticut.scenefile import BladeSpec, Material, load_scene, save_scene

FLESH = Material("flesh", "drag", drag_distance_mm=1.0)
BONE = Material("bone", "rigid")


@pytest.fixture(scope="module")
def nested_scene():
    """Bone (r 8) inside flesh (r 20) inside a box of air."""
    flesh = Region("flesh", *icosphere(20.0, 2), FLESH)
    bone = Region("bone", *icosphere(8.0, 1), BONE)
    blade = BladeSpec("scalpel", (-50.0, 0.0, 0.0), (50.0, 0.0, 0.0), 50)
    return build([flesh, bone], blades=[blade], settings=BuildSettings(accuracy_mm=0.3))


def test_nested_regions_give_each_tet_the_innermost_material(nested_scene):
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(60, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    # Radii well clear of the faceted surfaces (an icosphere's facets dip inside its radius).
    for radius, expected in ((0.0, "bone"), (5.0, "bone"), (11.0, "flesh"), (17.0, "flesh"),
                             (22.0, "air"), (24.0, "air")):  # fmt: skip
        points = directions * radius
        assert set(materials_at(nested_scene, points)) == {expected}, radius
    assert [m.name for m in nested_scene.materials] == ["air", "flesh", "bone"]
    assert nested_scene.materials[0].model == "free"


def test_build_report_counts_quality_valence_and_deviation(nested_scene):
    report = nested_scene.metadata["build_report"]
    counts = np.bincount(nested_scene.tet_materials, minlength=3)
    assert report["tets_per_material"] == {"air": counts[0], "flesh": counts[1], "bone": counts[2]}
    assert report["tets"] == len(nested_scene.tets) == sum(report["tets_per_material"].values())
    assert report["nesting"] == {"flesh": "", "bone": "flesh"}
    assert report["quality"]["inverted_or_flat"] == 0
    assert report["quality"]["min_dihedral_deg"] > 1.0
    assert report["quality"]["sliver_threshold_deg"] == 10.0
    assert 4 <= report["valence"]["max_tets_per_edge"] <= 30
    assert report["valence"]["mean_tets_per_vertex"] > 4
    assert report["repairs"] == {"flesh": {}, "bone": {}}
    for region in ("flesh", "bone"):
        assert report["deviation_mm"][region] <= report["settings"]["accuracy_mm"]
    assert set(report["timings_s"]) >= {"repair", "tetrahedralize", "label", "total"}
    assert nested_scene.blades[0].name == "scalpel"


def test_built_scene_survives_a_save_and_load(nested_scene, tmp_path):
    path = tmp_path / "nested.hapticut.msgpack"
    save_scene(nested_scene, path)
    loaded = load_scene(path)
    assert len(loaded.tets) == len(nested_scene.tets)
    np.testing.assert_array_equal(loaded.tet_materials, nested_scene.tet_materials)
    assert loaded.metadata["build_report"]["tets"] == len(nested_scene.tets)


def test_a_built_scene_stores_its_tets_along_a_hilbert_curve(nested_scene):
    vertices, tets = np.asarray(nested_scene.vertices), np.asarray(nested_scene.tets)
    assert np.all(np.diff(hilbert_keys(vertices[tets].mean(axis=1))) >= 0)
    first_use = np.unique(tets.ravel(), return_index=True)[1]
    assert np.all(np.diff(first_use) > 0) and len(first_use) == len(vertices)


@pytest.mark.parametrize("kind", ["box", "cube", "tetrahedron"])
def test_the_mesh_boundary_is_the_enclosure_and_its_tets_are_air(kind):
    vertices, faces = icosphere(10.0, 1)
    scene = build(
        [Region("ball", vertices, faces, BONE)],
        settings=BuildSettings(enclosure=kind, margin_mm=5.0, accuracy_mm=0.2),
    )
    enclosure = enclosure_surface(kind, vertices.min(axis=0), vertices.max(axis=0), 5.0)
    normals, offsets = enclosure_planes(*enclosure)
    assert len(normals) == (4 if kind == "tetrahedron" else 6)
    outer = boundary_faces(scene.tets)
    off_plane = np.abs(scene.vertices[np.unique(outer)] @ normals.T - offsets).min(axis=1)
    assert off_plane.max() < 1e-6
    outer_tets = np.flatnonzero(np.isin(np.sort(scene.tets, axis=1), outer).sum(axis=1) >= 3)
    assert np.all(scene.tet_materials[outer_tets] == 0)
    report = scene.metadata["build_report"]
    assert report["enclosure"]["faces"] == len(enclosure[1])
    assert report["boundary"]["boundary_area_relative_error"] < 1e-3
    if kind == "cube":
        assert np.ptp(np.ptp(np.asarray(enclosure[0]), axis=0)) < 1e-9  # equal sides


def test_adaptive_sizing_needs_fewer_tets_than_uniform():
    region = Region("ball", *icosphere(10.0, 2), BONE)
    common = dict(margin_mm=20.0, accuracy_mm=0.2, edge_near_mm=2.5)
    uniform = build([region], settings=BuildSettings(adaptive=False, **common))
    adaptive = build([region], settings=BuildSettings(edge_far_mm=12.0, **common))
    assert len(adaptive.tets) < 0.6 * len(uniform.tets)
    assert adaptive.metadata["build_report"]["settings"]["adaptive"] is True
    assert uniform.metadata["build_report"]["settings"]["adaptive"] is False


def test_a_refine_zone_makes_small_tets_along_a_blade_reach():
    region = Region("ball", *icosphere(10.0, 1), BONE)
    zone = RefineZone((-25.0, 0.0, 0.0), (-15.0, 0.0, 0.0), radius_mm=3.0, edge_mm=1.5)
    settings = BuildSettings(margin_mm=15.0, accuracy_mm=0.2, edge_near_mm=5.0, edge_far_mm=12.0)
    plain = build([region], settings=settings)
    refined = build([region], settings=replace(settings, refine=(zone,)))

    def edges_near_zone(scene):
        # How many tets lie within 4 mm of the zone's middle (a coarse mesh may have none),
        # and the mean edge of the four nearest it.
        distance = np.linalg.norm(scene.vertices[scene.tets].mean(axis=1) - [-20.0, 0, 0], axis=1)
        ends = scene.vertices[scene.tets[np.argsort(distance)[:4]]]
        return (distance < 4).sum(), np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1).mean()

    plain_count, plain_edge = edges_near_zone(plain)
    refined_count, refined_edge = edges_near_zone(refined)
    assert refined_count > 3 * max(plain_count, 1)
    assert refined_edge < plain_edge


def test_progress_runs_from_0_to_1_and_a_cancel_stops_the_build():
    region = Region("ball", *icosphere(10.0, 1), BONE)
    seen: list[tuple[float, str]] = []
    build(
        [region], settings=BuildSettings(accuracy_mm=0.2), progress=lambda f, m: seen.append((f, m))
    )
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert any("tetrahedraliz" in m for _, m in seen)

    polled = []

    def cancel_while_tetwild_runs(fraction, message):
        polled.append(message)
        return "fTetWild," not in message  # The messages polled while the child process runs.

    # No timed assertion (speed belongs to benchmarks): the build stops at the first poll
    # during fTetWild, and no later step runs.
    with pytest.raises(BuildCancelled):
        build([region], settings=BuildSettings(accuracy_mm=0.2), progress=cancel_while_tetwild_runs)
    assert "fTetWild," in polled[-1]
    assert sum("fTetWild," in m for m in polled) == 1


def test_a_meshing_beyond_the_accuracy_is_made_again_with_a_tighter_envelope(monkeypatch):
    """The builder holds every region's meshed surface within accuracy_mm of its input: an
    envelope of three times the accuracy (monkeypatched) lets fTetWild stray beyond it, and
    the builder meshes again with half the envelope until the surface is within."""
    monkeypatch.setattr(builder, "ENVELOPE_SHARE", 3.0)
    seen: list[tuple[float, str]] = []
    scene = build(
        [Region("ball", *icosphere(10.0, 2), BONE)],
        settings=BuildSettings(accuracy_mm=0.3),
        progress=lambda f, m: seen.append((f, m)),
    )
    report = scene.metadata["build_report"]
    attempts = report["meshing_attempts"]
    assert len(attempts) >= 2
    assert attempts[0]["envelope_mm"] == pytest.approx(0.9)
    assert attempts[0]["deviation_mm"]["ball"] > 0.3
    assert all(later["deviation_mm"]["ball"] > 0.3 for later in attempts[:-1])
    assert attempts[-1]["deviation_mm"] == report["deviation_mm"]
    assert report["deviation_mm"]["ball"] <= report["settings"]["accuracy_mm"] == 0.3
    assert report["settings"]["envelope_mm"] == pytest.approx(0.9 / 2 ** (len(attempts) - 1))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert any("meshing again with a 0.45 mm envelope" in m for _, m in seen)


def test_a_meshing_that_stays_beyond_the_accuracy_is_refused_in_strict_mode(monkeypatch):
    monkeypatch.setattr(builder, "ENVELOPE_SHARE", 3.0)
    monkeypatch.setattr(builder, "MESHING_ATTEMPTS", 1)
    with pytest.raises(BuildError, match=r"'ball'.*beyond accuracy_mm \(0\.3 mm\), after 1"):
        build(
            [Region("ball", *icosphere(10.0, 2), BONE)],
            settings=BuildSettings(accuracy_mm=0.3, strict_accuracy=True),
        )


def _labels_empty_for(monkeypatch, meshings: int) -> None:
    """The first ``meshings`` meshings label no tet inside any region, as when fTetWild merges
    a region's surfaces (its output differs between runs; this makes it happen on demand)."""
    label, calls = builder._label, []

    def emptied(*args):
        inside, tet_materials = label(*args)
        calls.append(1)
        if len(calls) > meshings:
            return inside, tet_materials
        return np.zeros_like(inside), np.zeros_like(tet_materials)

    monkeypatch.setattr(builder, "_label", emptied)


def test_a_meshing_that_leaves_a_region_without_tets_is_made_again(monkeypatch):
    _labels_empty_for(monkeypatch, 1)
    seen: list[str] = []
    scene = build(
        [Region("ball", *icosphere(10.0, 2), BONE)],
        settings=BuildSettings(accuracy_mm=1.0),
        progress=lambda f, m: seen.append(m),
    )
    report = scene.metadata["build_report"]
    attempts = report["meshing_attempts"]
    assert attempts[0] == {"envelope_mm": pytest.approx(0.4), "no_tet_inside": ["ball"]}
    assert attempts[1]["envelope_mm"] == pytest.approx(0.2)
    assert report["tets_per_region"]["ball"] > 0
    assert any("no tet inside ball (meshing 2 of 3)" in m for m in seen)


def test_a_region_left_without_tets_by_every_meshing_is_an_error(monkeypatch):
    _labels_empty_for(monkeypatch, builder.MESHING_ATTEMPTS)
    with pytest.raises(BuildError, match=r"'ball': no tet lies inside this region after 3 mesh"):
        build([Region("ball", *icosphere(10.0, 2), BONE)], settings=BuildSettings(accuracy_mm=1.0))


def test_regions_sharing_a_material_share_its_entry():
    left = Region("left", *icosphere(5.0, 1, centre=(-10, 0, 0)), BONE)
    right = Region("right", *icosphere(5.0, 1, centre=(10, 0, 0)), BONE)
    scene = build([left, right], settings=BuildSettings(accuracy_mm=0.2))
    assert [m.name for m in scene.materials] == ["air", "bone"]
    assert materials_at(scene, [[-10, 0, 0], [10, 0, 0], [0, 0, 0]]) == ["bone", "bone", "air"]
    assert scene.metadata["build_report"]["nesting"] == {"left": "", "right": ""}
    other_bone = Material("bone", "drag", drag_distance_mm=2.0)
    with pytest.raises(BuildError, match="'right'.*given twice"):
        build([left, Region("right", right.vertices, right.faces, other_bone)])


def test_the_bunny_scan_is_repaired_meshed_and_labelled():
    """A real scan through pymeshlab and fTetWild (coarse, so it stays quick)."""
    vertices, faces = read_surface(bunny_path())
    scale = 120.0 / float(np.ptp(vertices, axis=0).max())
    vertices = (vertices - vertices.mean(axis=0)) * scale
    scene = build(
        [Region("bunny", vertices, faces, BONE)],
        settings=BuildSettings(enclosure="cube", accuracy_mm=5.0, edge_far_mm=40.0),
    )
    report = scene.metadata["build_report"]
    assert report["repairs"]["bunny"]["boundary_edges_before"] == 109
    assert report["repairs"]["bunny"]["closed_holes"] == 5
    assert report["surfaces"]["bunny"]["faces_meshed"] < report["surfaces"]["bunny"]["faces_in"]
    assert report["deviation_mm"]["bunny"] <= 5.0
    # Points clearly inside or outside the input scan get body or air.
    rng = np.random.default_rng(7)
    points = rng.uniform(vertices.min(axis=0), vertices.max(axis=0), size=(1000, 3))
    winding = winding_numbers(points, vertices, faces)
    clear_inside = points[winding > 0.99]
    clear_outside = points[winding < 0.01]
    from hapticut.scenebuild.geometry import Surface
    from hapticut.scenebuild.repair import distance_to_surfaces

    surface = [Surface(vertices, faces)]
    far = 8.0  # beyond the 5 mm accuracy
    clear_inside = clear_inside[distance_to_surfaces(clear_inside, surface, far) >= far][:20]
    clear_outside = clear_outside[distance_to_surfaces(clear_outside, surface, far) >= far][:20]
    assert len(clear_inside) >= 3 and len(clear_outside) >= 3
    assert set(materials_at(scene, clear_inside)) == {"bone"}
    assert set(materials_at(scene, clear_outside)) == {"air"}


def test_a_scan_at_default_settings_models_the_air_only_as_far_as_needed():
    """The bunny scan, 100 mm long, built with the defaults: the air is modelled only as far
    as the scene needs it (docs/decisions.md), about half the tets, fTetWild's builds a few
    percent either side; an air that clearly outnumbers the body fails. The share is in the
    report."""
    vertices, faces = read_surface(bunny_path())
    vertices = (vertices - vertices.mean(axis=0)) * (100.0 / float(np.ptp(vertices, axis=0).max()))
    scene = build([Region("bunny", vertices, faces, BONE)])
    report = scene.metadata["build_report"]
    air = report["tets_per_material"]["air"]
    print(
        f"bunny 100 mm, defaults: {report['tets']} tets, air {100 * report['air_share']:.1f} %, "
        f"{report['timings_s']['total']:.1f} s, meshings {len(report['meshing_attempts'])}"
    )
    assert report["air_share"] == pytest.approx(air / report["tets"], abs=1e-4)
    assert report["air_share"] < 0.6
