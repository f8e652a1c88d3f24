"""The evaluation's cut memory figures (tools/evaluation/hapticut_evaluation/cut_memory.py),
driving the engine: a second pass back in the slit feels at most the cut variant, a pass
beside it the uncut flesh, and skin re-entered gives no breaking peak; the committed table
(docs/evaluation/cut_memory.csv) is what the evaluation gives."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from hapticut_evaluation import charts, report
from hapticut_evaluation import cut_memory as cm

COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "evaluation" / "cut_memory.csv"


@pytest.fixture(scope="module")
def slits():
    return cm.slit_passes()


@pytest.fixture(scope="module")
def presses():
    return cm.skin_passes()


@pytest.fixture(scope="module")
def rows(slits, presses):
    return cm.run_cut_memory(slits, presses)


def _row(rows: list[dict], scene: str, name: str) -> dict:
    (row,) = (r for r in rows if r["scene"] == scene and r["pass"] == name)
    return row


def test_the_second_pass_in_the_slit_feels_the_cut_variant_and_the_parallel_one_the_uncut(
    slits, rows
):
    first, second, parallel = (_row(rows, cm.FLESH, name) for name, _ in cm.SLIT_PASSES)
    uncut, cut = cm.K * cm.FLESH_DRAG_MM, cm.K * cm.FLESH_CUT_DRAG_MM
    # The first pass trails at the uncut drag deep in the slab, and cuts.
    assert first["peak_N"] == pytest.approx(uncut, rel=0.02)
    assert first["mean_N"] > 0.9 * uncut
    assert first["tets_cut"] > 10
    # Back in its slit: at most the cut variant's force, and that force (not air).
    assert second["peak_N"] <= cut + 1e-9
    assert second["mean_N"] > 0.5 * cut
    assert second["tets_cut"] == first["tets_cut"]  # Nothing new to cut in the slit.
    # Beside it the flesh is whole: the first pass's force again, and more tets cut.
    assert parallel["peak_N"] == pytest.approx(first["peak_N"], rel=0.02)
    assert parallel["mean_N"] == pytest.approx(first["mean_N"], rel=0.05)
    assert parallel["tets_cut"] > second["tets_cut"]
    # The rows are the traces' figures, read where the row says.
    x, force = slits[1]["x_mm"], slits[1]["force_N"]
    inside = (x >= cm.INSIDE_X_MM[0]) & (x <= cm.INSIDE_X_MM[1])
    assert second["peak_N"] == pytest.approx(force[inside].max(), abs=1e-4)
    assert inside.sum() > 500


def test_skin_re_entered_does_not_break_again_and_beside_it_does(rows):
    first, again, beside = (_row(rows, cm.SKIN, name) for name, _ in cm.SKIN_PASSES)
    # The first entry breaks the skin at its break force and opens it.
    assert first["peak_N"] == pytest.approx(cm.SKIN_BREAK_N, rel=0.02)
    assert first["tets_cut"] > 0
    # Re-entry at the same place: no breaking peak, at most the flesh under the opened skin.
    assert again["peak_N"] <= cm.K * cm.UNDER_SKIN_DRAG_MM + 1e-9
    assert again["peak_N"] < 0.5 * first["peak_N"]
    # Beside the opening the skin is whole: it breaks again.
    assert beside["peak_N"] == pytest.approx(first["peak_N"], rel=0.02)


def test_the_committed_table_is_the_evaluations(rows):
    with COMMITTED.open() as f:
        committed = list(csv.DictReader(f))
    assert [r["pass"] for r in committed] == [r["pass"] for r in rows]
    for saved, now in zip(committed, rows, strict=True):
        assert list(saved) == list(now)
        for key in ("peak_N", "mean_N", "stroke_peak_N", "uncut_bound_N", "cut_bound_N"):
            assert float(saved[key]) == pytest.approx(now[key], abs=1e-3), (now["pass"], key)
        assert int(saved["tets_cut"]) == now["tets_cut"]


def test_the_chart_and_the_page_section_are_made(tmp_path, slits, presses, rows):
    charts.cut_memory(slits, presses, tmp_path / "cut_memory.png")
    assert (tmp_path / "cut_memory.png").stat().st_size > 10_000
    section = report.cut_memory_section(report.load_blocks(), rows)
    assert "$" not in section
    for row in rows:
        assert f"| {row['scene']} | {row['pass']} |" in section
    assert np.isfinite([r["peak_N"] for r in rows]).all()
