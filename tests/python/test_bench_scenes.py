"""`hapticut bench blade` finds the example scenes where they are, or says it found none."""

from pathlib import Path

import pytest
from hapticut import _core
from hapticut.bench import blade

SOURCE_SCENES = sorted(
    p.name for p in (Path(__file__).resolve().parents[2] / "examples").glob("*.hapticut.*")
)


def test_the_installed_package_ships_every_example_scene():
    paths, found = blade.example_scenes()
    assert SOURCE_SCENES, "the source tree has example scenes"
    assert sorted(p.name for p in paths) == SOURCE_SCENES
    assert paths[0].parent == blade.PACKAGED_EXAMPLES, found
    assert f"{len(SOURCE_SCENES)} in" in found


def test_a_scenes_directory_is_used_and_an_empty_one_is_reported(tmp_path):
    paths, found = blade.example_scenes(tmp_path)
    assert paths == []
    assert "NO EXAMPLE SCENES FOUND" in found and str(tmp_path) in found
    with pytest.raises(FileNotFoundError, match="no such directory"):
        blade.example_scenes(tmp_path / "missing")
    (tmp_path / "one.hapticut.msgpack").write_bytes(
        (blade.PACKAGED_EXAMPLES / "sphere80.hapticut.msgpack").read_bytes()
    )
    paths, found = blade.example_scenes(tmp_path)
    assert [p.name for p in paths] == ["one.hapticut.msgpack"]
    labels = [label for label, _ in blade.scenes(paths)]
    assert labels[0].startswith("one, cut") and labels[-1].startswith("grid")


def test_every_example_scene_runs_a_50_point_stroke_without_a_capped_point():
    """The bunny once needed 70 transitions in one tick and was capped; the work budget
    lets the paper's independent points finish. Counts, not times: times belong to the
    benchmark's table."""
    paths, _ = blade.example_scenes()
    for label, space in blade.scenes(paths):
        poses = blade.stroke_poses(space)
        result = blade.time_ticks(space, 50, poses, repeats=1, coupling="independent")
        assert int(result["capped_points"].sum()) == 0, label
        assert int(result["tick_transitions"].max()) <= int(result["budget"]), label


def test_every_example_scene_runs_a_rigid_50_point_stroke_within_its_bounds():
    """The rigid blade (the default) on the same strokes: the points' walks keep the work
    budget and the pose's rounds their bound, on every tick."""
    paths, _ = blade.example_scenes()
    for label, space in blade.scenes(paths):
        poses = blade.stroke_poses(space)
        result = blade.time_ticks(space, 50, poses, repeats=1)
        assert int(result["tick_transitions"].max()) <= int(result["budget"]), label
        rounds = result["rigid_rounds"]
        assert 0 < int(rounds.max()) <= _core.BLADE_MAX_RIGID_ROUNDS, label


def test_the_blade_table_has_a_row_per_scene_and_coupling(tmp_path):
    (tmp_path / "one.hapticut.msgpack").write_bytes(
        (blade.PACKAGED_EXAMPLES / "sphere80.hapticut.msgpack").read_bytes()
    )
    text = blade.run(find_max=False, rounds=1, scenes_dir=tmp_path)
    lines = [line for line in text.splitlines() if line.startswith("|") and "---" not in line]
    rows = [[cell.strip() for cell in line.split("|")[1:-1]] for line in lines[1:]]
    assert lines[0].split("|")[2].strip() == "coupling"
    couplings = [(row[0].split(",")[0], row[1]) for row in rows]
    assert couplings == [
        (scene, coupling)
        for scene in ("one", "one", "grid ~12k tets", blade.CREASE_LABEL)
        for coupling in ("rigid", "independent")
    ]
    # In contact: none where the bodies are cut, some where they are rigid; the same
    # ticks for both couplings, and the rigid row gives the ratio.
    headers = [cell.strip() for cell in lines[0].split("|")[1:-1]]
    column = {name: i for i, name in enumerate(headers)}
    contact = [row[column["contact ticks"]] for row in rows]
    assert contact[0] == contact[1] == "0"
    assert contact[2] == contact[3] and int(contact[2].replace(",", "")) > 0
    assert contact[6] == contact[7] and int(contact[6].replace(",", "")) > 0
    assert rows[6][column["rigid / independent in contact"]].endswith("x")
    # Cut memory: the strokes through tissue cut it (the cut scene and the grid), the rigid
    # ones cut nothing; the extra cost is the row's figure less the blade's without memory.
    first = column["tets cut"]
    assert headers[first : first + len(blade.CUT_MEMORY_HEADERS)] == blade.CUT_MEMORY_HEADERS
    cut = [int(row[column["tets cut"]]) for row in rows]
    assert all(n > 10 for n in cut[0:2] + cut[4:6]), cut
    assert cut[2:4] == cut[6:8] == [0, 0]
    for row in rows:
        with_memory, without = (
            _number(row[column[name]])
            for name in ("median ns/tick", "median ns/tick without cut memory")
        )
        assert without > 0
        extra = _number(row[column["cut memory +median ns"]])
        assert extra == pytest.approx(with_memory - without, abs=1.0 + 0.01 * abs(extra))
        percent = _number(row[column["cut memory +median %"]])
        assert percent == pytest.approx(100 * extra / without, abs=0.01 + 0.01 * abs(percent))
        _number(row[column["cut memory +p99 ns"]])


def _number(cell: str) -> float:
    """A figure of the table as format_table printed it."""
    return float(cell.replace(",", ""))


def test_a_blade_without_cut_memory_cuts_nothing_on_the_stroke_one_with_it_cuts():
    space = blade._grid_space()
    poses = blade.stroke_poses(space)
    for coupling in blade.COUPLINGS:
        remembering = blade.time_ticks(space, 50, poses, repeats=1, coupling=coupling)
        forgetting = blade.time_ticks(
            space, 50, poses, repeats=1, coupling=coupling, cut_memory=False
        )
        assert remembering["cut_tets"] > 50, coupling
        assert forgetting["cut_tets"] == 0, coupling
        assert len(forgetting["tick_ns"]) == len(poses)


def test_the_crease_stroke_rests_the_blade_in_the_groove():
    """Pressed 1 mm into the generated groove and slid along it, the rigid blade rests on
    both flanks with every tick resolved."""
    result = blade.time_ticks(blade.crease_space(), 50, blade.crease_poses(), repeats=1)
    slide = slice(len(blade.crease_poses()) - 200, None)
    assert (result["contacts"][slide] >= 2).all()
    assert int(result["unresolved"].sum()) == 0


def test_the_points_search_stops_at_the_most_a_blade_takes():
    """A budget every count fits ends the search at the blade's limit, not at a refusal."""
    paths, _ = blade.example_scenes(None)
    label, space = next(iter(blade.scenes(paths[:1])))
    poses = blade.stroke_poses(space)[:40]
    most = blade.max_points_within(space, poses, budget_ns=1e15, coupling="independent")
    assert most == _core.BLADE_MAX_POINTS, label
