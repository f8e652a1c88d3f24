"""The evaluation's page (tools/evaluation/hapticut_evaluation/page.md filled in by
report.py): rendered from the committed run's CSV files, every placeholder gets a figure,
every block of the template is used, and the tables carry the rows they were given."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from hapticut_evaluation import meshes, paths, report, valence

COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "evaluation"


def _value(text: str):
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def committed(name: str) -> list[dict]:
    with (COMMITTED / f"{name}.csv").open() as f:
        return [{k: _value(v) for k, v in row.items()} for row in csv.DictReader(f)]


@pytest.fixture(scope="module")
def share():
    # A real stroke's transition counts, on a Kuhn grid with a rigid block (no fTetWild).
    axis = np.linspace(-45.0, 45.0, 7)
    scene = meshes.grid_scene("block", axis, axis, axis, ((-15, -15, -15), (15, 15, 15)))
    path, _ = paths.press_and_slide(0.001, points=2, radius_mm=15.0, slide_s=0.2)
    return valence.stroke_share(scene, path)


def render(tmp_path: Path, share: dict, *, quick: bool) -> str:
    valence_rows = committed("valence")
    report.write_page(
        tmp_path,
        accuracy_rows=committed("accuracy"),
        drag_rows=committed("drag_lag"),
        stability_rows=committed("stability"),
        loop_rows=committed("closed_loop"),
        valence_rows=valence_rows,
        valence_fit=valence.fit(valence_rows),
        valence_share=share,
        economy_rows=committed("mesh_economy"),
        example_rows=committed("example_economy"),
        shading_rows=committed("example_shading"),
        blade_shading_rows=committed("rigid_blade_shading"),
        rigid_rows=committed("rigid_blade"),
        penetration_rows=committed("edge_penetration"),
        cut_memory_rows=committed("cut_memory"),
        quick=quick,
        elapsed_s=12.3,
    )
    return (tmp_path / "README.md").read_text()


def test_the_page_has_a_figure_for_every_placeholder(tmp_path, share):
    page = render(tmp_path, share, quick=False)
    assert "$" not in page
    assert "This is a --quick run" not in page
    assert "12 s" in page  # the elapsed time given
    assert f"{share['ticks']} point updates" in page
    for name in ("accuracy", "stability", "closed_loop", "mesh_economy", "example_economy"):
        first = committed(name)[0]
        label = first.get("label") or first.get("scenario") or first.get("variant")
        if label is None:
            label = first["method"]
        assert f"| {label} |" in page, name
    assert "## The rigid blade against independent points" in page
    for row in committed("rigid_blade_shading"):
        assert f"| {row['example']} | {row['points']} |" in page
    for row in committed("edge_penetration"):
        assert f"| {row['scene']} | {row['method']} |" in page
    assert "## Cut memory: a second pass in the slit" in page
    for row in committed("cut_memory"):
        assert f"| {row['scene']} | {row['pass']} |" in page


def test_every_block_of_the_template_is_used():
    source = Path(report.__file__).read_text()
    blocks = report.load_blocks()
    assert "page" in blocks
    unused = [name for name in blocks if f'"{name}"' not in source]
    assert unused == []


def test_a_missing_figure_is_named(share):
    blocks = report.load_blocks()
    with pytest.raises(KeyError, match="total"):
        report.fill(blocks, "target_invariants", failed=0)


def test_a_quick_run_says_so(tmp_path, share):
    assert "**This is a --quick run" in render(tmp_path, share, quick=True)
