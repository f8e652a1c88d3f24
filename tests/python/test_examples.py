"""The committed example scenes load in the engine with the right materials in the right places.

Rebuilding them (fTetWild, about 30 s for all) is the slow test at the end.
"""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from build_test_support import EXAMPLES
from hapticut import engine

NAMES = ("sphere80", "sphere320", "mouse", "finger")
# Points known to lie in each material (mm), well clear of every surface.
KNOWN_POINTS = {
    "sphere80": {"body": [[0, 0, 0], [10, 5, -8]], "air": [[0, 0, 40], [40, 40, 40]]},
    "sphere320": {"body": [[0, 0, 0], [0, 20, 0]], "air": [[0, 0, 36], [-40, 40, -40]]},
    "finger": {
        "bone": [[-20, 0, 0], [2, 0, 0], [22, 0, 0]],
        "flesh": [[-20, 0, 5.5], [2, -5.5, 0], [-8, 0, 0]],
        "skin": [[-20, 0, 8.25], [0, 8.0, 0]],
        "air": [[-20, 0, 11], [0, 12, 0], [44, 0, 0]],
    },
}


def example(name):
    return EXAMPLES / f"{name}.hapticut.msgpack"


@pytest.mark.parametrize("name", NAMES)
def test_example_loads_in_the_engine_as_built(name):
    scene, space = engine.load_space(example(name))
    report = scene.metadata["build_report"]
    assert space.tet_count == report["tets"] == len(scene.tets)
    assert space.stats["reoriented_tets"] == 0
    assert space.stats["max_tets_per_edge"] == report["valence"]["max_tets_per_edge"]
    assert space.stats["min_dihedral_deg"] == pytest.approx(
        report["quality"]["min_dihedral_deg"], abs=1e-3
    )
    names = space.material_names
    counts = np.bincount(space.tet_materials, minlength=len(names))
    assert dict(zip(names, counts.tolist(), strict=True)) == report["tets_per_material"]
    assert names[0] == "air" and scene.materials[0].model == "free"
    assert scene.blades and scene.blades[0].points == 50
    assert scene.metadata["example"]["name"] == name


@pytest.mark.parametrize("name", sorted(KNOWN_POINTS))
def test_example_materials_at_known_points(name):
    scene, space = engine.load_space(example(name))
    for material, points in KNOWN_POINTS[name].items():
        tets = space.locate(np.array(points, dtype=float))
        assert np.all(tets >= 0), (material, points)
        found = [space.material_names[space.tet_materials[t]] for t in tets]
        assert found == [material] * len(points), (name, material)


def test_mouse_labels_follow_the_scan():
    """Points the bunny scan clearly holds are body; clearly outside, air."""
    build_examples = load_build_examples()
    from hapticut.scenebuild.geometry import Surface, winding_numbers
    from hapticut.scenebuild.repair import distance_to_surfaces

    region = build_examples.mouse_region()
    scene, space = engine.load_space(example("mouse"))
    rng = np.random.default_rng(11)
    points = rng.uniform(region.vertices.min(axis=0), region.vertices.max(axis=0), (600, 3))
    clear = distance_to_surfaces(points, [Surface(region.vertices, region.faces)], 6.0) >= 6.0
    winding = winding_numbers(points[clear], region.vertices, region.faces)
    names = np.array(space.material_names)[space.tet_materials[space.locate(points[clear])]]
    assert np.all(names[winding > 0.99] == "body") and (winding > 0.99).sum() >= 10
    assert np.all(names[winding < 0.01] == "air") and (winding < 0.01).sum() >= 10


def test_the_spheres_keep_the_papers_faces_and_sit_near_table3():
    for name, faces, paper_tets in (("sphere80", 80, 394), ("sphere320", 320, 1917)):
        scene, _ = engine.load_space(example(name))
        report = scene.metadata["build_report"]
        assert report["surfaces"][name]["faces_meshed"] == faces
        assert paper_tets / 2 < report["tets"] < paper_tets * 2  # fTetWild, not the paper's mesher


def load_build_examples():
    spec = importlib.util.spec_from_file_location("build_examples", EXAMPLES / "build_examples.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("build_examples", module)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_examples_rebuild_from_their_sources(name):
    build_examples = load_build_examples()
    scene, _ = build_examples.build_example(name)
    committed = engine.load_space(example(name))[0].metadata["build_report"]
    report = scene.metadata["build_report"]
    assert 0.5 * committed["tets"] < report["tets"] < 2 * committed["tets"]
    assert set(report["tets_per_material"]) == set(committed["tets_per_material"])
    space = engine.space_from_scene(scene)
    for material, points in KNOWN_POINTS.get(name, {}).items():
        tets = space.locate(np.array(points, dtype=float))
        assert [space.material_names[space.tet_materials[t]] for t in tets] == [material] * len(
            points
        )
