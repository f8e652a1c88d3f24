"""Write the evaluation's CSV files and its Markdown page: the prose is page.md's
blocks, every figure in it computed here from the run's rows (charts: charts.py)."""

from __future__ import annotations

import csv
import inspect
import math
import os
import re
import string
from pathlib import Path

from hapticut import _core

from hapticut_evaluation import (
    accuracy,
    economy,
    example_shading,
    meshes,
    methods,
    paths,
    stability,
    surface,
)

COMMAND = "python -m hapticut_evaluation --out docs/evaluation"
TEMPLATE = Path(__file__).with_name("page.md")

# The evaluation's targets (the page's "Targets, as measured").
SHADING_TARGET_DEG = 0.3
SHADING_RATE_RATIO = 1.5
SPEED_TARGET = 10.0
# Cited, not measured: the paper's Table 2 (its set-ups and its transition times).
PAPER_EDGE_TETS, PAPER_VERTEX_TETS = 12, 20
PAPER_EDGE_US, PAPER_VERTEX_US = 160, 490

_BLOCK = re.compile(r"^<!-- block: (\w+) -->$", re.MULTILINE)


def load_blocks(path: Path = TEMPLATE) -> dict[str, string.Template]:
    """page.md's blocks by name: the text after each marker line up to the next."""
    text = path.read_text()
    marks = list(_BLOCK.finditer(text))
    blocks = {}
    for mark, following in zip(marks, [*marks[1:], None], strict=True):
        end = following.start() if following else len(text)
        blocks[mark.group(1)] = string.Template(text[mark.end() + 1 : end].rstrip("\n"))
    return blocks


def fill(blocks: dict[str, string.Template], name: str, **values) -> str:
    """One block with its figures (a missing figure raises KeyError)."""
    return blocks[name].substitute(values)


def write_csv(path: Path, rows: list[dict]) -> None:
    if not rows:
        return
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)


def _fmt(x, digits=3) -> str:
    if isinstance(x, float):
        return f"{x:.{digits}g}"
    return str(x)


def markdown_table(rows: list[dict], columns: list[tuple[str, str]]) -> str:
    head = "| " + " | ".join(title for _, title in columns) + " |"
    rule = "|" + "|".join("---" for _ in columns) + "|"
    body = ["| " + " | ".join(_fmt(r[key]) for key, _ in columns) + " |" for r in rows]
    return "\n".join([head, rule, *body])


def _met(ok: bool) -> str:
    return "met" if ok else "NOT met"


def _span(values, digits=2, unit="") -> str:
    return f"{min(values):.{digits}f}{unit} to {max(values):.{digits}f}{unit}"


def _row(accuracy_rows, family, faces, rate=1000.0):
    for r in accuracy_rows:
        if r["method"] == family and r["faces"] == faces and r["rate_Hz"] == rate:
            return r
    return None


def cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def build_kind() -> str:
    """How hapticut._core was compiled, from the module itself."""
    if _core.BUILT_NATIVE:
        return "for this CPU (HAPTICUT_NATIVE=ON, as the test command builds it)"
    return "portable (HAPTICUT_NATIVE=OFF, as for wheels)"


def targets(b, accuracy_rows: list[dict], stability_rows: list[dict]) -> list[str]:
    lines = []
    faces = 320
    shaded_1k = _row(accuracy_rows, methods.SHADED, faces, 1000.0)
    shaded_50 = _row(accuracy_rows, methods.SHADED, faces, 50.0)
    if shaded_1k and shaded_50:
        e1, e50 = shaded_1k["dir_err_mean_deg"], shaded_50["dir_err_mean_deg"]
        lines.append(
            fill(
                b,
                "target_shading",
                faces=faces,
                e1k=f"{e1:.3f}",
                target_deg=f"{SHADING_TARGET_DEG:g}",
                met_1k=_met(e1 <= SHADING_TARGET_DEG),
                e50=f"{e50:.3f}",
                ratio=f"{e50 / e1:.2f}",
                target_ratio=f"{SHADING_RATE_RATIO:g}",
                met_50=_met(e50 <= SHADING_RATE_RATIO * e1),
            )
        )
    ours = [r for r in stability_rows if r["family"] in (methods.TET, methods.SHADED)]
    failed = [r for r in ours if r["verdict"] != "pass"]
    lines.append(fill(b, "target_invariants", failed=len(failed), total=len(ours)))
    for f in sorted({r["faces"] for r in accuracy_rows if r["faces"]}):
        god, mine = _row(accuracy_rows, methods.GOD, f), _row(accuracy_rows, methods.TET, f)
        if not (god and mine):
            continue
        ratio = god["ns_per_update"] / mine["ns_per_update"]
        accurate = mine["dir_err_mean_deg"] <= god["dir_err_mean_deg"]
        lines.append(
            fill(
                b,
                "target_speed",
                faces=f,
                ratio=f"{ratio:.1f}",
                ours_ns=f"{mine['ns_per_update']:.0f}",
                god_ns=f"{god['ns_per_update']:.0f}",
                accuracy="equal or better" if accurate else "worse",
                ours_deg=f"{mine['dir_err_mean_deg']:.2f}",
                god_deg=f"{god['dir_err_mean_deg']:.2f}",
                ours_mm=f"{mine['pos_err_mean_mm']:.3g}",
                god_mm=f"{god['pos_err_mean_mm']:.3g}",
                target_speed=f"{SPEED_TARGET:g}",
                met=_met(ratio >= SPEED_TARGET and accurate),
            )
        )
    matched = matched_accuracy(accuracy_rows)
    other = [m for m in matched if (m[1]["method"], m[1]["faces"]) != (methods.TET, m[0]["faces"])]
    if matched and not other:
        lines.append(fill(b, "target_matched_same"))
    for god, mine, ratio in other:
        lines.append(
            fill(
                b,
                "target_matched",
                god_faces=god["faces"],
                god_deg=f"{god['dir_err_mean_deg']:.2f}",
                god_ns=f"{god['ns_per_update']:.0f}",
                ours_method=mine["method"],
                ours_faces=mine["faces"],
                ours_deg=f"{mine['dir_err_mean_deg']:.3f}",
                ours_ns=f"{mine['ns_per_update']:.0f}",
                ratio=f"{ratio:.1f}",
                target_speed=f"{SPEED_TARGET:g}",
                met=_met(ratio >= SPEED_TARGET),
            )
        )
    slow = _ratios(accuracy_rows, methods.TET, 50.0)
    if slow:
        lines.append(
            fill(
                b,
                "target_slow",
                low=f"{min(slow.values()):.1f}",
                high=f"{max(slow.values()):.1f}",
                target_speed=f"{SPEED_TARGET:g}",
                met=_met(min(slow.values()) >= SPEED_TARGET),
            )
        )
    return lines


def never_worse_target(b, shading_rows: list[dict], example_rows: list[dict]) -> list[str]:
    """The target for force shading, as measured: shading never worse than the plain proxy."""
    if not shading_rows:
        return []
    scenes = [(r["example"], r["never_worse"]) for r in shading_rows]
    variants = example_shading.economy_never_worse(example_rows)
    failed = [name for name, ok in scenes + variants if not ok]
    return [
        fill(
            b,
            "target_never_worse",
            scenes_ok=sum(ok for _, ok in scenes),
            scenes=len(scenes),
            variants_ok=sum(ok for _, ok in variants),
            variants=len(variants),
            met="met" if not failed else "NOT met: " + ", ".join(failed),
        )
    ]


def _ratios(accuracy_rows, family, rate=1000.0) -> dict[int, float]:
    """God-object ns / `family` ns per sphere, at `rate`, where both ran."""
    out = {}
    for f in sorted({r["faces"] for r in accuracy_rows if r["faces"]}):
        god, mine = _row(accuracy_rows, methods.GOD, f, rate), _row(accuracy_rows, family, f, rate)
        if god and mine:
            out[f] = god["ns_per_update"] / mine["ns_per_update"]
    return out


def scene_sizing(b, accuracy_rows: list[dict], economy_rows: list[dict]) -> str:
    """How fine the sphere scenes are meshed, against the finest uniform mesh of the
    mesh economy (same sphere, measured in the same run)."""
    tets = {r["faces"]: r["tets"] for r in accuracy_rows if r["method"] == methods.TET}
    uniform = [r for r in economy_rows if not r["adaptive"] and "cube" in r["variant"]]
    if not tets or not uniform:
        return ""
    fine = min(uniform, key=lambda r: r["edge_mm"])
    here = _row(accuracy_rows, methods.TET, fine["faces"])
    if here is None:
        return ""
    return fill(
        b,
        "scene_sizing",
        cube_mm=f"{2 * meshes.CUBE_HALF_MM:g}",
        edge_mm=f"{meshes.SPHERE_EDGE_MM:g}",
        tets=", ".join(f"{f} faces: {n} tets" for f, n in sorted(tets.items())),
        faces=fine["faces"],
        fine_mm=f"{fine['edge_mm']:g}",
        fine_tets=fine["tets"],
        fine_kib=f"{fine['memory_bytes'] / 1024:.0f}",
        tets_here=here["tets"],
        kib_here=f"{here['memory_bytes'] / 1024:.0f}",
        fine_ns=f"{fine['ns_per_update']:.0f}",
        ns_here=f"{here['ns_per_update']:.0f}",
    )


def speed_gap(b, accuracy_rows: list[dict], *, quick: bool = False) -> str:
    """The >= 10x target against the god-object: the ratios, and where the time goes."""
    ratios = _ratios(accuracy_rows, methods.TET)
    if not ratios:
        return ""
    faces = list(ratios)
    shaded = _ratios(accuracy_rows, methods.SHADED)
    slow = _ratios(accuracy_rows, methods.TET, 50.0)

    def span(d):
        return _span(d.values(), 1, "x")

    def ns(family, f):
        return f"{_row(accuracy_rows, family, f)['ns_per_update']:.0f}"

    return fill(
        b,
        "speed_gap",
        target_speed=f"{SPEED_TARGET:g}",
        span=span(ratios),
        per_model=", ".join(f"{f} faces {r:.1f}x" for f, r in ratios.items()),
        met_every="met" if min(ratios.values()) >= SPEED_TARGET else "NOT met",
        shaded_span=span(shaded) if shaded else "(not run)",
        slow=fill(b, "speed_gap_slow", span=span(slow), target_speed=f"{SPEED_TARGET:g}")
        if slow
        else "",
        strokes=_default(accuracy.run_accuracy, "points"),
        warm_passes=accuracy.WARM_PASSES,
        min_seconds=f"{0.0 if quick else accuracy.TIMING_MIN_S:g}",
        build_kind=build_kind(),
        tet_ns_low=ns(methods.TET, faces[0]),
        tet_ns_high=ns(methods.TET, faces[-1]),
        faces_low=faces[0],
        faces_high=faces[-1],
        god_ns_low=ns(methods.GOD, faces[0]),
        god_ns_high=ns(methods.GOD, faces[-1]),
    )


def _default(function, name):
    """A keyword's default: the figure the run used unless told otherwise."""
    return inspect.signature(function).parameters[name].default


def matched_accuracy(accuracy_rows: list[dict], rate: float = 1000.0) -> list[tuple]:
    """For each god-object model: the fastest model of ours (tet proxy, with or
    without force shading, any sphere) whose mean direction error is no worse,
    and how many times faster it is. (god row, our row, ratio) per god-object model."""
    ours = [
        r
        for r in accuracy_rows
        if r["method"] in (methods.TET, methods.SHADED) and r["rate_Hz"] == rate
    ]
    out = []
    for god in (r for r in accuracy_rows if r["method"] == methods.GOD and r["rate_Hz"] == rate):
        good = [r for r in ours if r["dir_err_mean_deg"] <= god["dir_err_mean_deg"]]
        if good:
            best = min(good, key=lambda r: r["ns_per_update"])
            out.append((god, best, god["ns_per_update"] / best["ns_per_update"]))
    return out


def _pivot(rows: list[dict], element: str, cases: list[str]) -> list[dict]:
    """One row per fan, one column per case (widen: mean and max over targets)."""
    out = []
    for mesh in dict.fromkeys(r["mesh"] for r in rows if r["element"] == element):
        sel = {r["case"]: r for r in rows if r["element"] == element and r["mesh"] == mesh}
        row = {"mesh": mesh, "valence": next(iter(sel.values()))["valence"]}
        for case in cases:
            if case in sel:
                row[case] = sel[case]["ns"]
                if case == "widen":
                    row["widen_max"] = sel[case]["ns_max"]
        out.append(row)
    return out


def sphere_sizing(b, rows: list[dict]) -> str:
    """What the sphere's sizing rows say: the fastest and slowest mesh, and their errors."""
    if len(rows) < 2:
        return ""
    ranked = sorted(rows, key=lambda r: r["ns_per_update"])
    errors = [r["dir_err_mean_deg"] for r in rows]
    fast, slow = ranked[0], ranked[-1]
    return fill(
        b,
        "sphere_sizing",
        err_low=f"{min(errors):.2f}",
        err_high=f"{max(errors):.2f}",
        order=", ".join(f"{r['variant']} {r['ns_per_update']:.0f} ns" for r in ranked),
        ratio=f"{slow['ns_per_update'] / fast['ns_per_update']:.1f}",
        small=" and ".join(f"the {r['variant']} mesh" for r in ranked[-2:][::-1]),
        edge_mm=f"{meshes.SPHERE_EDGE_MM:g}",
    )


def _depths(depths: dict[str, float]) -> str:
    """The press depths per example, as the page names them."""
    names = {"mouse": "bunny", "finger": "the finger's bones"}
    by_depth: dict[float, list[str]] = {}
    for name, depth in depths.items():
        by_depth.setdefault(depth, []).append(names.get(name, name))
    return ", ".join(f"{', '.join(n)} {d:g} mm" for d, n in by_depth.items())


def _strokes_values() -> dict:
    return {
        "strokes": _default(economy.example_economy, "points"),
        "slide_s": f"{economy.EXAMPLE_SLIDE_S:g}",
        "speed_mm_s": f"{_default(surface.strokes, 'speed_mm_s'):g}",
    }


def rigid_blade_shading(b, rows: list[dict], blade_rows: list[dict]) -> str:
    """The rigid blade's rows on the example spheres, beside the shaded independent points'."""
    if not blade_rows:
        return ""
    from hapticut_evaluation import rigid_blade

    own = {r["example"]: r for r in rows}
    table_rows = []
    for r in blade_rows:
        points = own.get(r["example"], {})
        table_rows.append(
            {
                **r,
                "points_own_mean": points.get(f"{example_shading.OWN}_dir_err_smooth_mean_deg", ""),
                "points_own_p95": points.get(f"{example_shading.OWN}_dir_err_smooth_p95_deg", ""),
            }
        )
    return fill(
        b,
        "example_shading_rigid",
        blade_mm=f"{rigid_blade.SHADING_BLADE_MM:g}",
        table=markdown_table(
            table_rows,
            [
                ("example", "example"),
                ("points", "blade points"),
                ("plain_dir_err_smooth_mean_deg", "plain mean deg"),
                ("plain_dir_err_smooth_p95_deg", "p95"),
                ("shaded_dir_err_smooth_mean_deg", "shaded mean deg"),
                ("shaded_dir_err_smooth_p95_deg", "p95"),
                ("points_own_mean", "independent points, shaded mean deg"),
                ("points_own_p95", "p95"),
                ("contact_updates", "ticks in contact"),
                ("unresolved_ticks", "unresolved"),
            ],
        ),
    )


def example_shading_section(b, rows: list[dict], blade_rows: list[dict] = ()) -> str:
    if not rows:
        return ""
    P, OWN, S = example_shading.PLAIN, example_shading.OWN, example_shading.SOURCE
    columns = [("example", "example"), ("tets", "tets")]
    for kind, title in ((P, "plain"), (OWN, "own surface"), (S, "source")):
        columns += [
            (f"{kind}_dir_err_smooth_mean_deg", f"{title} mean deg"),
            (f"{kind}_dir_err_smooth_p95_deg", "p95"),
        ]
    columns += [
        (f"{P}_ns_per_update", "plain ns"),
        (f"{OWN}_ns_per_update", "own ns"),
        (f"{S}_ns_per_update", "source ns"),
        ("never_worse", "never worse"),
    ]
    gains = [
        r[f"{P}_dir_err_smooth_mean_deg"] - r[f"{k}_dir_err_smooth_mean_deg"]
        for r in rows
        for k in (OWN, S)
    ]
    cost = [r[f"{k}_ns_per_update"] - r[f"{P}_ns_per_update"] for r in rows for k in (OWN, S)]
    shown = {r["example"] for r in rows}
    depths = {k: v for k, v in example_shading.DEPTH_MM.items() if k in shown}
    return fill(
        b,
        "example_shading",
        **_strokes_values(),
        depths=_depths(depths),
        table=markdown_table(rows, columns),
        gain_low=f"{min(gains):.2f}",
        gain_high=f"{max(gains):.2f}",
        cost_low=f"{min(cost):.0f}",
        cost_high=f"{max(cost):.0f}",
        rigid_blade=rigid_blade_shading(b, rows, list(blade_rows)),
    )


EXAMPLE_COLUMNS = [
    ("example", "example"),
    ("variant", "variant"),
    ("tets", "tets"),
    ("boundary_faces", "boundary faces"),
    ("build_s", "build s"),
    ("tetwild_s", "fTetWild s"),
    ("memory_bytes", "bytes"),
    ("tet_ns_per_update", "ns/update"),
    ("tet_dir_err_facet_mean_deg", "facet mean deg"),
    ("tet_dir_err_facet_p95_deg", "p95"),
    ("tet_dir_err_smooth_mean_deg", "smooth mean deg"),
    ("tet_dir_err_smooth_p95_deg", "p95"),
    ("shaded_ns_per_update", "shaded ns"),
    ("shaded_dir_err_smooth_mean_deg", "shaded mean deg"),
    ("shaded_dir_err_smooth_p95_deg", "p95"),
    ("own_dir_err_smooth_mean_deg", "own-shaded mean deg"),
    ("own_dir_err_smooth_p95_deg", "p95"),
    ("max_tets_per_vertex", "max vertex valence"),
]


def examples_section(b, rows: list[dict]) -> str:
    """Mesh economy on the examples (the bunny as the paper's mouse, the layered finger)."""
    if not rows:
        return ""
    folds, error_spread, lines = [], [], []
    for example in dict.fromkeys(r["example"] for r in rows):
        every = [r for r in rows if r["example"] == example]
        sel = [r for r in every if "accuracy" not in r["variant"]]
        if not sel:
            continue
        tets = [r["tets"] for r in sel]
        folds.append(max(tets) / min(tets))
        smooth = [r["tet_dir_err_smooth_mean_deg"] for r in sel]
        error_spread.append(max(smooth) - min(smooth))
        line = fill(
            b,
            "example_line",
            example=example,
            tets_low=min(tets),
            tets_high=max(tets),
            fold=f"{max(tets) / min(tets):.1f}",
            build_span=_span([r["build_s"] for r in sel], 1),
            ns_span=_span([r["tet_ns_per_update"] for r in sel], 0),
            smooth_span=_span(smooth),
            facet_span=_span([r["tet_dir_err_facet_mean_deg"] for r in sel]),
            shaded_span=_span([r["shaded_dir_err_smooth_mean_deg"] for r in sel]),
            own_span=_span([r["own_dir_err_smooth_mean_deg"] for r in sel]),
        )
        cube = next((r for r in sel if r["variant"] == "adaptive, cube"), None)
        tet = next((r for r in sel if r["variant"] == "adaptive, bounding tet"), None)
        if cube and tet:
            line += fill(
                b,
                "example_enclosures",
                tet_tets=tet["tets"],
                cube_tets=cube["tets"],
                tet_faces=tet["boundary_faces"],
                cube_faces=cube["boundary_faces"],
            )
        for r in every:
            if "accuracy" in r["variant"] and cube:
                line += fill(
                    b,
                    "example_finer",
                    finer=r["variant"].split(", ")[-1],
                    tets=r["tets"],
                    build_s=f"{r['build_s']:.0f}",
                    facet=f"{r['tet_dir_err_facet_mean_deg']:.2f}",
                    facet_was=f"{cube['tet_dir_err_facet_mean_deg']:.2f}",
                    smooth=f"{r['tet_dir_err_smooth_mean_deg']:.2f}",
                    shaded=f"{r['shaded_dir_err_smooth_mean_deg']:.2f}",
                    shaded_was=f"{cube['shaded_dir_err_smooth_mean_deg']:.2f}",
                )
        lines.append(line)
    shown = {r["example"] for r in rows}
    return fill(
        b,
        "examples",
        cpus=cores(),
        **_strokes_values(),
        depths=_depths({k: v for k, v in economy.EXAMPLE_DEPTH_MM.items() if k in shown}),
        table=markdown_table(rows, EXAMPLE_COLUMNS),
        per_example="\n".join(lines),
        spread=f"{max(error_spread, default=0.0):.1f}",
        fold_low=f"{min(folds, default=1.0):.0f}",
        fold_high=f"{max(folds, default=1.0):.0f}",
        shading_note=shading_note(b, rows),
    )


def shading_note(b, rows: list[dict]) -> str:
    """Item 3 of the examples' economy: what force shading does on them, from the rows."""
    mouse = [r for r in rows if r["example"] == "mouse" and "accuracy" not in r["variant"]]
    finger = [r for r in rows if r["example"] == "finger"]
    if not mouse:
        return ""

    def gain(sel, kind):
        return _span(
            [r["tet_dir_err_smooth_mean_deg"] - r[f"{kind}_dir_err_smooth_mean_deg"] for r in sel]
        )

    smooth = [r["tet_dir_err_smooth_mean_deg"] for r in mouse]
    text = fill(
        b,
        "shading_note",
        low=f"{min(smooth):.2f}",
        high=f"{max(smooth):.2f}",
        gain_source=gain(mouse, "shaded"),
        gain_own=gain(mouse, "own"),
    )
    if finger:
        text += fill(
            b,
            "shading_note_finger",
            gain_source=gain(finger, "shaded"),
            gain_own=gain(finger, "own"),
        )
    return text


def valence_section(b, rows: list[dict], fits: list[dict], share: dict) -> str:
    """Tables of EDGE and VERTEX transition cost against valence, the linear fits,
    and the answer to the paper's open question drawn from them."""
    if not rows:
        return ""
    fit = {(f["element"], f["case"]): f for f in fits}

    def per_tet(element, case):
        f = fit.get((element, case))
        return f"{f['ns_per_tet']:.1f}" if f else "?"

    def at(element, case, n):
        f = fit.get((element, case))
        return f["ns_fixed"] + f["ns_per_tet"] * n if f else float("nan")

    # A regular tet's corner (solid angle) and dihedral angle: how many fit around a
    # vertex and an edge.
    corner_sr = math.acos(23.0 / 27.0)
    dihedral_deg = math.degrees(math.acos(1.0 / 3.0))
    edge_table = markdown_table(
        _pivot(rows, "edge", ["widen", "scan", "face"]),
        [
            ("mesh", "edge fan"),
            ("valence", "tets"),
            ("widen", "widen ns"),
            ("widen_max", "widen max"),
            ("scan", "scan ns"),
            ("face", "-> FACE ns"),
        ],
    )
    vertex_table = markdown_table(
        _pivot(rows, "vertex", ["widen", "stay", "face", "edge"]),
        [
            ("mesh", "vertex fan"),
            ("valence", "tets"),
            ("widen", "widen ns"),
            ("widen_max", "widen max"),
            ("stay", "stay ns"),
            ("face", "-> FACE ns"),
            ("edge", "-> EDGE ns"),
        ],
    )
    fit_table = markdown_table(
        fits,
        [
            ("element", "element"),
            ("case", "case"),
            ("ns_fixed", "fixed ns"),
            ("ns_per_tet", "ns per tet"),
            ("r2", "R^2"),
        ],
    )
    mean_e, mean_v = share["mean_tets_per_edge"], share["mean_tets_per_vertex"]
    return fill(
        b,
        "valence",
        edge_table=edge_table,
        vertex_table=vertex_table,
        fit_table=fit_table,
        r2=f"{min(f['r2'] for f in fits):.3f}",
        edge_per_tet=per_tet("edge", "scan"),
        vertex_per_tet=per_tet("vertex", "stay"),
        paper_edge_tets=PAPER_EDGE_TETS,
        paper_vertex_tets=PAPER_VERTEX_TETS,
        edge_ns=f"{at('edge', 'scan', PAPER_EDGE_TETS):.0f}",
        vertex_ns=f"{at('vertex', 'stay', PAPER_VERTEX_TETS):.0f}",
        paper_edge_us=PAPER_EDGE_US,
        paper_vertex_us=PAPER_VERTEX_US,
        ticks=share["ticks"],
        per_tick=f"{share['transitions_per_tick']:.2f}",
        edge_per_tick=f"{share['edge_per_tick']:.3f}",
        vertex_per_tick=f"{share['vertex_per_tick']:.3f}",
        mean_e=f"{mean_e:.1f}",
        max_e=share["max_tets_per_edge"],
        mean_v=f"{mean_v:.1f}",
        max_v=share["max_tets_per_vertex"],
        edge_add=f"{share['edge_per_tick'] * at('edge', 'face', mean_e):.1f}",
        regular_vertex=f"{4 * math.pi / corner_sr:.0f}",
        corner_sr=f"{corner_sr:.2f}",
        regular_edge=f"{360.0 / dihedral_deg:.0f}",
        dihedral_deg=f"{dihedral_deg:.1f}",
        worst_ratio=f"{share['max_tets_per_vertex'] / mean_v:.1f}",
    )


def rigid_blade_section(b, stiffness_rows: list[dict], penetration_rows: list[dict]) -> str:
    """The rigid blade's stiffness against the length of edge over bone, and the ideal edge's
    penetration into bone, both against the paper's independent points."""
    if not stiffness_rows:
        return ""
    from hapticut_evaluation import rigid_blade

    whole = max(stiffness_rows, key=lambda r: r["points_over_bone"])
    least = min(stiffness_rows, key=lambda r: r["points_over_bone"])
    return fill(
        b,
        "rigid_blade",
        points=rigid_blade.POINTS,
        spacing_mm=f"{rigid_blade.SPACING_MM:g}",
        k=f"{rigid_blade.K:g}",
        press_mm=f"{rigid_blade.PRESS_MM:g}",
        soft=f"{whole['independent_points_N_per_mm'] / least['independent_points_N_per_mm']:.0f}",
        samples=rigid_blade.SAMPLES_PER_SPACING,
        on_surface_mm=f"{rigid_blade.ON_SURFACE_MM:g}",
        stiffness_table=markdown_table(
            stiffness_rows,
            [
                ("points_over_bone", "points over bone"),
                ("n_k_N_per_mm", "n k N/mm"),
                ("independent_points_N_per_mm", "independent N/mm"),
                ("rigid_free_N_per_mm", "rigid, free N/mm"),
                ("rigid_locked_N_per_mm", "rigid, locked N/mm"),
            ],
        ),
        penetration_table=markdown_table(
            penetration_rows,
            [
                ("scene", "scene"),
                ("method", "blade"),
                ("strokes", "strokes"),
                ("ticks", "ticks"),
                ("ticks_with_edge_in_bone", "ticks with edge in bone"),
                ("edge_samples", "edge samples"),
                ("edge_samples_in_bone", "in bone"),
                ("deepest_mm", "deepest mm"),
            ],
        ),
    )


def cut_memory_section(b, rows: list[dict]) -> str:
    """The force along a first pass, a second in its slit and a parallel one through flesh cut
    to a tenth, and the skin's breaking peak on first entry against re-entry."""
    if not rows:
        return ""
    from hapticut_evaluation import cut_memory as cm

    def peak(scene: str, name: str) -> str:
        (row,) = (r for r in rows if r["scene"] == scene and r["pass"] == name)
        return f"{row['peak_N']:.3g}"

    slit = [name for name, _ in cm.SLIT_PASSES]
    skin = [name for name, _ in cm.SKIN_PASSES]
    return fill(
        b,
        "cut_memory",
        k=f"{cm.K:g}",
        speed_mm_s=f"{cm.SPEED_MM_S:g}",
        grid_mm=f"{cm.GRID_MM:g}",
        jitter_pct=f"{cm.GRID_JITTER * 100:g}",
        drag_mm=f"{cm.FLESH_DRAG_MM:g}",
        cut_drag_mm=f"{cm.FLESH_CUT_DRAG_MM:g}",
        depth_mm=f"{-cm.SLIT_Z_MM:g}",
        slab_mm=f"{2 * cm.FLESH_HALF_MM:g}",
        beside_mm=f"{cm.BESIDE_MM:g}",
        break_N=f"{cm.SKIN_BREAK_N:g}",
        skin_mm=f"{cm.SKIN_MM:g}",
        under_mm=f"{cm.UNDER_SKIN_DRAG_MM:g}",
        inside=f"{cm.INSIDE_X_MM[0]:g} to {cm.INSIDE_X_MM[1]:g} mm",
        table=markdown_table(
            rows,
            [
                ("scene", "scene"),
                ("pass", "pass"),
                ("beside_mm", "beside mm"),
                ("read", "read"),
                ("peak_N", "peak N"),
                ("mean_N", "mean N"),
                ("stroke_peak_N", "stroke peak N"),
                ("tets_cut", "tets cut"),
                ("uncut_bound_N", "uncut N"),
                ("cut_bound_N", "cut N"),
            ],
        ),
        first_N=peak(cm.FLESH, slit[0]),
        second_N=peak(cm.FLESH, slit[1]),
        parallel_N=peak(cm.FLESH, slit[2]),
        break_first_N=peak(cm.SKIN, skin[0]),
        reentry_N=peak(cm.SKIN, skin[1]),
        break_beside_N=peak(cm.SKIN, skin[2]),
    )


FILES = (
    "accuracy.csv",
    "drag_lag.csv",
    "stability.csv",
    "closed_loop.csv",
    "mesh_economy.csv",
    "example_economy.csv",
    "example_shading.csv",
    "rigid_blade_shading.csv",
    "valence.csv",
    "speed_vs_error.png",
    "valence.png",
    "rigid_blade.csv",
    "edge_penetration.csv",
    "rigid_stiffness.png",
    "cut_memory.csv",
    "cut_memory.png",
)


def write_page(
    out: Path,
    *,
    accuracy_rows,
    drag_rows,
    stability_rows,
    loop_rows,
    valence_rows,
    valence_fit,
    valence_share,
    economy_rows,
    example_rows=(),
    shading_rows=(),
    blade_shading_rows=(),
    rigid_rows=(),
    penetration_rows=(),
    cut_memory_rows=(),
    quick: bool,
    elapsed_s: float,
) -> None:
    b = load_blocks()
    example_rows, shading_rows = list(example_rows), list(shading_rows)
    target_lines = targets(b, accuracy_rows, stability_rows)
    target_lines += never_worse_target(b, shading_rows, example_rows)
    page = fill(
        b,
        "page",
        command=COMMAND,
        elapsed_s=f"{elapsed_s:.0f}",
        cpus=cores(),
        build_kind=build_kind(),
        quick_note="\n" + fill(b, "quick_note").strip("\n") + "\n" if quick else "",
        targets="\n".join(target_lines),
        speed_gap=speed_gap(b, accuracy_rows, quick=quick),
        tet=methods.TET,
        shaded=methods.SHADED,
        god=methods.GOD,
        voxel=methods.VOXEL,
        scene_sizing=scene_sizing(b, accuracy_rows, economy_rows),
        radius_mm=f"{meshes.SPHERE_RADIUS_MM:g}",
        press_mm=f"{paths.PRESS_DEPTH_MM:g}",
        speed_mm_s=f"{paths.SLIDE_SPEED_MM_S:g}",
        strokes=_default(accuracy.run_accuracy, "points"),
        accuracy_table=markdown_table(
            accuracy_rows,
            [
                ("label", "method"),
                ("model", "model"),
                ("rate_Hz", "Hz"),
                ("ns_per_update", "ns/update"),
                ("memory_bytes", "bytes"),
                ("dir_err_mean_deg", "dir mean deg"),
                ("dir_err_p95_deg", "p95"),
                ("dir_err_max_deg", "max"),
                ("pos_err_mean_mm", "pos mean mm"),
                ("penetration_max_mm", "penetration mm"),
            ],
        ),
        drag_mm=", ".join(
            f"{d:g}" for d in dict.fromkeys(r["drag_distance_mm"] for r in drag_rows)
        ),
        drag_table=markdown_table(
            drag_rows,
            [
                ("method", "method"),
                ("model", "model"),
                ("rate_Hz", "Hz"),
                ("lag_mean_mm", "lag mean mm"),
                ("lag_min_mm", "min"),
                ("lag_max_mm", "max"),
            ],
        ),
        stability_table=markdown_table(
            stability_rows,
            [
                ("scenario", "scenario"),
                ("method", "method"),
                ("verdict", "verdict"),
                ("ticks", "ticks"),
                ("figure", "figure"),
            ],
        ),
        hand_kg=f"{stability.HAND_MASS_KG:g}",
        hand_damping=f"{stability.HAND_DAMPING_N_S_PER_MM * 1000.0:g}",
        grip=f"{stability.HAND_STIFFNESS_N_PER_MM:g}",
        hand_press_mm=f"{stability.HAND_PRESS_MM:g}",
        chatter_pct=f"{stability.CHATTER_SHARE * 100:g}",
        chatter_min_N=f"{stability.CHATTER_MIN_N:g}",
        energy_pct=f"{stability.ENERGY_SHARE * 100:g}",
        loop_table=markdown_table(
            loop_rows,
            [
                ("k_N_per_mm", "k N/mm"),
                ("method", "method"),
                ("verdict", "verdict"),
                ("energy_gained_mJ", "energy mJ"),
                ("hold_force_N", "hold force N"),
                ("hold_ripple_N", "ripple N"),
            ],
        ),
        economy_faces=", ".join(str(f) for f in dict.fromkeys(r["faces"] for r in economy_rows)),
        economy_table=markdown_table(
            economy_rows,
            [
                ("variant", "variant"),
                ("tets", "tets"),
                ("build_s", "build s"),
                ("memory_bytes", "bytes"),
                ("ns_per_update", "ns/update"),
                ("dir_err_mean_deg", "dir mean deg"),
                ("max_tets_per_edge", "max edge valence"),
                ("max_tets_per_vertex", "max vertex valence"),
            ],
        ),
        sphere_sizing=sphere_sizing(b, economy_rows),
        example_shading=example_shading_section(b, shading_rows, list(blade_shading_rows)),
        examples=examples_section(b, example_rows),
        valence=valence_section(b, valence_rows, valence_fit, valence_share),
        rigid_blade=rigid_blade_section(b, list(rigid_rows), list(penetration_rows)),
        cut_memory=cut_memory_section(b, list(cut_memory_rows)),
        files=", ".join(f"`{name}`" for name in FILES if (out / name).exists()) + ".",
    )
    (out / "README.md").write_text(page + "\n")
