"""Write the evaluation's CSV files, the chart (PNG) and the markdown page."""

from __future__ import annotations

import csv
from pathlib import Path

from hapticut.evaluation import example_shading, meshes, methods

COMMAND = "hapticut evaluate --out docs/evaluation"


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


def chart(accuracy_rows: list[dict], out: Path) -> None:
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (speed, memory) = plt.subplots(1, 2, figsize=(12, 5))
    styles = {methods.TET: "o-", methods.SHADED: "s-", methods.GOD: "^-", methods.VOXEL: "D--"}
    for family, style in styles.items():
        rows = [r for r in accuracy_rows if r["method"] == family and r["rate_Hz"] == 1000.0]
        if not rows:
            continue
        rows.sort(key=lambda r: (r["faces"], -r["voxel_mm"]))
        x = [r["ns_per_update"] for r in rows]
        y = [max(r["dir_err_mean_deg"], 1e-3) for r in rows]
        speed.plot(x, y, style, label=family)
        memory.plot([r["memory_bytes"] / 1024 for r in rows], y, style, label=family)
        for k, (r, xi, yi) in enumerate(zip(rows, x, y, strict=True)):
            tag = f"{r['voxel_mm']:g} mm" if family == methods.VOXEL else str(r["faces"])
            offset = (4, 3)
            if family == methods.VOXEL:
                # The voxel sizes sit close together: label the first and last only.
                if 0 < k < len(rows) - 1:
                    continue
                offset = (-14, -12) if k == 0 else (2, -12)
            speed.annotate(tag, (xi, yi), textcoords="offset points", xytext=offset, fontsize=7)
            memory.annotate(
                tag,
                (r["memory_bytes"] / 1024, yi),
                textcoords="offset points",
                xytext=(4, 3) if family != methods.VOXEL else (-8, -12),
                fontsize=7,
            )
    for ax in (speed, memory):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("mean force-direction error (deg), 1 kHz")
        ax.grid(True, which="both", alpha=0.3)
    # Plain tick labels on the time axis (the log scale's minor labels overlap).
    ticks = [t for t in (10, 20, 50, 100, 200, 500, 1000, 2000, 5000)]
    speed.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
    speed.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    speed.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    speed.axhline(0.3, color="grey", lw=0.8, ls=":")
    speed.annotate(
        "0.3 deg: issue 4's shading target",
        (speed.get_xlim()[0], 0.3),
        textcoords="offset points",
        xytext=(2, 3),
        fontsize=7,
        color="grey",
    )
    speed.set_xlabel("ns per point update (wall clock)")
    speed.set_title("Speed against accuracy, sphere r = 30 mm (labels: faces / voxel size)")
    memory.set_xlabel("memory of the method's model (KiB)")
    memory.set_title("Memory against accuracy")
    speed.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def targets(accuracy_rows: list[dict], stability_rows: list[dict]) -> list[str]:
    def row(family, faces, rate):
        for r in accuracy_rows:
            if r["method"] == family and r["faces"] == faces and r["rate_Hz"] == rate:
                return r
        return None

    lines = []
    shaded_1k, shaded_50 = row(methods.SHADED, 320, 1000.0), row(methods.SHADED, 320, 50.0)
    if shaded_1k and shaded_50:
        e1, e50 = shaded_1k["dir_err_mean_deg"], shaded_50["dir_err_mean_deg"]
        lines.append(
            f"- Force shading, 320-face sphere: mean direction error {e1:.3f} deg at 1 kHz "
            f"(target <= 0.3: {'met' if e1 <= 0.3 else 'NOT met'}); {e50:.3f} deg at 50 Hz, "
            f"{e50 / e1:.2f}x (target <= 1.5x: {'met' if e50 <= 1.5 * e1 else 'NOT met'})."
        )
    ours = [r for r in stability_rows if r["family"] in (methods.TET, methods.SHADED)]
    failed = [r for r in ours if r["verdict"] != "pass"]
    lines.append(
        f"- Fall-through or broken invariant of the tet proxy: {len(failed)} of {len(ours)} "
        f"verdicts failed (target: none)."
    )
    for faces in sorted({r["faces"] for r in accuracy_rows if r["faces"]}):
        god, ours_row = row(methods.GOD, faces, 1000.0), row(methods.TET, faces, 1000.0)
        if not (god and ours_row):
            continue
        ratio = god["ns_per_update"] / ours_row["ns_per_update"]
        accurate = ours_row["dir_err_mean_deg"] <= god["dir_err_mean_deg"]
        lines.append(
            f"- {faces} faces, same facets, 1 kHz: the tet proxy is {ratio:.1f}x faster per "
            f"point update than the god-object with its tree "
            f"({ours_row['ns_per_update']:.0f} vs {god['ns_per_update']:.0f} ns), at "
            f"{'equal or better' if accurate else 'worse'} direction accuracy "
            f"({ours_row['dir_err_mean_deg']:.2f} vs {god['dir_err_mean_deg']:.2f} deg; "
            f"position error {ours_row['pos_err_mean_mm']:.3g} vs "
            f"{god['pos_err_mean_mm']:.3g} mm, the tet mesh's surface being fTetWild's, "
            f"within its envelope) (target >= 10x: "
            f"{'met' if ratio >= 10 and accurate else 'NOT met'})."
        )
    matched = matched_accuracy(accuracy_rows)
    other = [m for m in matched if (m[1]["method"], m[1]["faces"]) != (methods.TET, m[0]["faces"])]
    if matched and not other:
        lines.append(
            "- At matched direction accuracy across models, the fastest model of ours at "
            "least as accurate as each god-object model is the tet proxy on the same "
            "facets: the lines above."
        )
    for god, ours_row, ratio in other:
        lines.append(
            f"- At equal or better direction accuracy, against the god-object on "
            f"{god['faces']} faces ({god['dir_err_mean_deg']:.2f} deg, "
            f"{god['ns_per_update']:.0f} ns): our fastest model that is at least as "
            f"accurate, {ours_row['method']} on {ours_row['faces']} faces "
            f"({ours_row['dir_err_mean_deg']:.3f} deg, {ours_row['ns_per_update']:.0f} ns), "
            f"is {ratio:.1f}x faster (target >= 10x: {'met' if ratio >= 10 else 'NOT met'})."
        )
    slow = [
        row(methods.GOD, f, 50.0)["ns_per_update"] / row(methods.TET, f, 50.0)["ns_per_update"]
        for f in sorted({r["faces"] for r in accuracy_rows if r["faces"]})
        if row(methods.GOD, f, 50.0) and row(methods.TET, f, 50.0)
    ]
    if slow:
        lines.append(
            f"- At 50 Hz the tet proxy is {min(slow):.1f}x to {max(slow):.1f}x faster per "
            "point update than the god-object at 50 Hz (each update of ours walks several "
            "tets). The 10x target is read at the servo's 1 kHz; at 50 Hz it is "
            f"{'met' if min(slow) >= 10 else 'NOT met'}."
        )
    return lines


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


def scene_sizing(accuracy_rows: list[dict]) -> list[str]:
    """The note on how fine the sphere scenes are meshed, with their tet counts."""
    tets = {r["faces"]: r["tets"] for r in accuracy_rows if r["method"] == methods.TET}
    if not tets:
        return []
    return [
        f"- **Scenes**: the icosphere (rigid) in a 90 mm cube of air, tetrahedralized by "
        f"fTetWild with a target edge of {meshes.SPHERE_EDGE_MM:g} mm. fTetWild refines only "
        "where the facets require it, so each mesh is no finer than its scene needs ("
        + ", ".join(f"{f} faces: {n} tets" for f, n in sorted(tets.items()))
        + "). When this generator was written, a 6 mm target gave the 80-face scene 40k tets "
        "(16 MB instead of 1.1 MB) for the same accuracy, and its 50 Hz update took 3.5x "
        "longer: the walk crossed more, colder tets."
    ]


def speed_gap(accuracy_rows: list[dict]) -> list[str]:
    """The >= 10x target against the god-object: the ratios, and where the time goes."""

    def ns(family, faces, rate=1000.0):
        for r in accuracy_rows:
            if r["method"] == family and r["faces"] == faces and r["rate_Hz"] == rate:
                return r["ns_per_update"]
        return None

    faces = sorted(
        {r["faces"] for r in accuracy_rows if r["faces"] and ns(methods.GOD, r["faces"])}
    )
    if not faces or not all(ns(methods.TET, f) for f in faces):
        return []
    ratios = {f: ns(methods.GOD, f) / ns(methods.TET, f) for f in faces}
    shaded = {f: ns(methods.GOD, f) / ns(methods.SHADED, f) for f in faces if ns(methods.SHADED, f)}
    slow = {
        f: ns(methods.GOD, f, 50.0) / ns(methods.TET, f, 50.0)
        for f in faces
        if ns(methods.TET, f, 50.0) and ns(methods.GOD, f, 50.0)
    }
    god_ns = [ns(methods.GOD, f) for f in faces]
    tet_ns = [ns(methods.TET, f) for f in faces]
    span = lambda d: f"{min(d.values()):.1f}x to {max(d.values()):.1f}x"  # noqa: E731
    lines = [
        "### The 10x target against the god-object",
        f"At 1 kHz, on the same facets, the tet proxy is {span(ratios)} faster per point "
        f"update than the god-object with its tree "
        f"({', '.join(f'{f} faces {r:.1f}x' for f, r in ratios.items())}). "
        + (
            "The target is met on every model."
            if min(ratios.values()) >= 10
            else "The target is NOT met on every model."
        )
        + f" With force shading on the same facets the proxy is {span(shaded)} faster; "
        "the god-object here has no force shading, which would cost it a similar amount "
        "and improve its direction error as much, so that ratio is not the target's "
        "comparison."
        + (
            f" At 50 Hz the bare proxy is {span(slow)} faster than the god-object at 50 Hz: "
            "the 10x target is read at the servo's 1 kHz."
            if slow
            else ""
        ),
        "",
        "How it is timed: each method runs the same 8 strokes in C++; a round times every "
        "method in turn, three passes each with the first warming the caches (a servo loop "
        "revisits the same few tets), and each method keeps its best round of at least "
        "3 s of rounds. This machine is shared and has slow spells lasting seconds; in "
        "them the proxy's update slowed by about 1.6x and the god-object's by about "
        "1.2x (its time is mostly waiting on branches and memory, which a busy "
        "neighbour slows less), so a ratio measured inside a spell is up to a quarter "
        "lower. Best rounds compare the two outside the spells. The engine and the "
        "baselines here are built for this CPU (HAPTICUT_NATIVE=ON, as the test command "
        "builds them); a portable build, the default for wheels, measured 12.5x to 16.3x "
        "on the day this generator was written.",
        "",
        f"Where the time goes. Ours grows from {tet_ns[0]:.0f} to {tet_ns[-1]:.0f} ns "
        f"from {faces[0]} to {faces[-1]} faces: a sliding update is one settled FACE "
        "transition (the neighbour is rigid, so (a-1) refuses at once; the target is "
        "projected on the face; the exit test takes q' against the three other planes) "
        "plus the tick's bookkeeping, about 330 instructions in all (callgrind, 80-face "
        "stroke, measured when this generator was written), and where a stroke crosses a "
        "tet edge an EDGE transition walks the edge's fan (about 780 instructions); a "
        "finer surface has smaller tets at it, so more edges are crossed. The "
        f"god-object grows from {god_ns[0]:.0f} to {god_ns[-1]:.0f} ns as its tree deepens: "
        "every tick it descends its tree twice (the segment q -> p, then q -> the "
        "constrained target) and re-solves its constraints from scratch. At 50 Hz "
        "each update of ours walks several tets (2 transitions per tet) and the ratio "
        "shrinks; a coarse mesh keeps that walk short (see the scene sizing note "
        "under Methods).",
        "",
    ]
    return lines


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


def sphere_sizing_note(rows: list[dict]) -> list[str]:
    """What the sphere's sizing rows say: the fastest and slowest mesh, and their errors."""
    if len(rows) < 2:
        return []
    ranked = sorted(rows, key=lambda r: r["ns_per_update"])
    errors = [r["dir_err_mean_deg"] for r in rows]
    fast, slow = ranked[0], ranked[-1]
    order = ", ".join(f"{r['variant']} {r['ns_per_update']:.0f} ns" for r in ranked)
    return [
        f"The error stays within {min(errors):.2f} to {max(errors):.2f} deg: the sphere's "
        f"facets set it, not the tets. The update does not: from fastest to slowest, "
        f"{order} ({slow['ns_per_update'] / fast['ns_per_update']:.1f}x). What slows it is "
        "small tets at the surface, not the mesh's size: a slide crosses more tet edges "
        "(each an EDGE transition that walks a fan) where the tets it slides on are "
        "small, as in the adaptive mesh (2 mm at the sphere) and the 3 mm one. This is why "
        f"the accuracy section meshes the spheres at a {meshes.SPHERE_EDGE_MM:g} mm target.",
        "",
    ]


def example_section(rows: list[dict]) -> list[str]:
    """Mesh economy on the examples (the bunny as the paper's mouse, the layered finger)."""
    if not rows:
        return []
    lines = [
        "### The examples: the bunny (the paper's mouse) and the layered finger",
        "Built by `hapticut.scenebuild` through `examples/build_examples.py` with its "
        "settings, the sizing and enclosure overridden per row (adaptive: the example's "
        "edge length at the surfaces growing to its far length; uniform: one length "
        "everywhere). Build s: the whole build (repair, simplification, fTetWild, labels, "
        "report), once, on 2 shared cores; fTetWild s: its share. Strokes: 8 presses "
        "into the rigid surface (bunny 2 mm, the finger's bones 1 mm, every other "
        "material made free so the force is the contact force alone), then 0.5 s of "
        "sliding at 100 mm/s that follows the surface, 1 kHz. No formula gives the truth "
        "here: the error is the angle between the force and the source surface's normal "
        "at the closest source point to the proxy, its facet normal (`facet`) and the "
        "normal interpolated from its vertex normals (`smooth`, the surface the facets "
        "sample); force shading is measured against `smooth`, with normals from the source "
        "(`shaded`) and from the scene's own rigid surface (`own-shaded`).",
        "",
        markdown_table(
            rows,
            [
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
            ],
        ),
        "",
    ]

    def span(values, digits=2):
        return f"{min(values):.{digits}f} to {max(values):.{digits}f}"

    folds, error_spread = [], []
    for example in dict.fromkeys(r["example"] for r in rows):
        every = [r for r in rows if r["example"] == example]
        sel = [r for r in every if "accuracy" not in r["variant"]]
        if not sel:
            continue
        tets = [r["tets"] for r in sel]
        folds.append(max(tets) / min(tets))
        smooth = [r["tet_dir_err_smooth_mean_deg"] for r in sel]
        error_spread.append(max(smooth) - min(smooth))
        line = (
            f"- **{example}**, sizing and enclosure: {min(tets)} to {max(tets)} tets "
            f"({max(tets) / min(tets):.1f}x), built in {span([r['build_s'] for r in sel], 1)} s, "
            f"updates of {span([r['tet_ns_per_update'] for r in sel], 0)} ns; mean error "
            f"against the smooth normal {span([r['tet_dir_err_smooth_mean_deg'] for r in sel])} "
            f"deg (facet {span([r['tet_dir_err_facet_mean_deg'] for r in sel])}), with force "
            f"shading {span([r['shaded_dir_err_smooth_mean_deg'] for r in sel])} deg (from "
            f"its own surface {span([r['own_dir_err_smooth_mean_deg'] for r in sel])})."
        )
        cube = next((r for r in sel if r["variant"] == "adaptive, cube"), None)
        tet = next((r for r in sel if r["variant"] == "adaptive, bounding tet"), None)
        if cube and tet:
            line += (
                f" Bounding tet against cube (adaptive): {tet['tets']} against {cube['tets']} "
                f"tets, {tet['boundary_faces']} against {cube['boundary_faces']} boundary faces."
            )
        for r in every:
            if "accuracy" in r["variant"] and cube:
                line += (
                    f" A finer surface ({r['variant'].split(', ')[-1]}): {r['tets']} tets "
                    f"built in {r['build_s']:.0f} s; facet error "
                    f"{r['tet_dir_err_facet_mean_deg']:.2f} deg (was "
                    f"{cube['tet_dir_err_facet_mean_deg']:.2f}), smooth "
                    f"{r['tet_dir_err_smooth_mean_deg']:.2f}, with force shading "
                    f"{r['shaded_dir_err_smooth_mean_deg']:.2f} (was "
                    f"{cube['shaded_dir_err_smooth_mean_deg']:.2f})."
                )
        lines.append(line)
    lines += [
        "",
        "What this says:",
        "1. **The air's sizing hardly moves the force error**: "
        f"{max(error_spread, default=0.0):.1f} deg at most across "
        f"{min(folds, default=1.0):.0f}- to {max(folds, default=1.0):.0f}-fold ranges of "
        "tets (the rows above). The rigid surface stays "
        "within fTetWild's envelope whatever the sizing, and the proxy slides on that "
        "surface. Sizing moves tets, memory, build time and the update (more tet edges "
        "crossed where tets are small, colder caches in a bigger mesh): the economical "
        "mesh is as fine at the surfaces as their own detail needs (adaptive sizing) and "
        "coarse elsewhere.",
        "2. **The bounding tet does not pay here.** fTetWild splits the enclosure's faces "
        "down to the far edge length, and a tet around the same objects has more area and "
        "volume than a cube or a box, so it ends with more boundary faces and more tets. "
        "The paper's argument (4 entry faces instead of 12) assumed the enclosure's faces "
        "left whole; and with the boundary tree, OUTSIDE's entry cost is logarithmic in "
        "the boundary faces anyway.",
        *_shading_note(rows),
        "",
    ]
    return lines


def _shading_note(rows: list[dict]) -> list[str]:
    """Item 3 of the examples' economy: what force shading does on them, from the rows."""
    mouse = [r for r in rows if r["example"] == "mouse" and "accuracy" not in r["variant"]]
    finger = [r for r in rows if r["example"] == "finger"]
    if not mouse:
        return []

    def gain(sel, kind):
        values = [
            r["tet_dir_err_smooth_mean_deg"] - r[f"{kind}_dir_err_smooth_mean_deg"] for r in sel
        ]
        return f"{min(values):.2f} to {max(values):.2f}"

    line = (
        "3. **The surface sets the error.** On the bunny at its own accuracy the facets "
        "differ from the scan's normals by "
        f"{min(r['tet_dir_err_smooth_mean_deg'] for r in mouse):.2f} to "
        f"{max(r['tet_dir_err_smooth_mean_deg'] for r in mouse):.2f} deg, most of it the "
        "scan's own bumps, finer than the facets, which no shading of those facets can "
        "follow. Force shading, its normals smoothed at the facets' scale with creases "
        f"kept, lowers the mean error by {gain(mouse, 'shaded')} deg from the source and "
        f"{gain(mouse, 'own')} deg from the scene's own surface (negative: worse). "
        "A finer surface lowers the error itself, at the price of tets and build time."
    )
    if finger:
        line += (
            f" On the finger's smooth bones shading lowers it by {gain(finger, 'shaded')} deg "
            f"(source) and {gain(finger, 'own')} deg (own surface)."
        )
    return [line]


def valence_section(rows: list[dict], fits: list[dict], share: dict) -> list[str]:
    """Tables of EDGE and VERTEX transition cost against valence, the linear fits,
    and the answer to the paper's open question drawn from them."""
    if not rows:
        return []
    fit = {(f["element"], f["case"]): f for f in fits}

    def per_tet(element, case):
        f = fit.get((element, case))
        return f"{f['ns_per_tet']:.1f}" if f else "?"

    def at(element, case, n):
        f = fit.get((element, case))
        return f["ns_fixed"] + f["ns_per_tet"] * n if f else float("nan")

    edge_cases = ["widen", "scan", "face"]
    vertex_cases = ["widen", "stay", "face", "edge"]
    mean_e, mean_v = share["mean_tets_per_edge"], share["mean_tets_per_vertex"]
    edge_cost = at("edge", "face", mean_e)
    lines = [
        "### One EDGE or VERTEX transition against valence (`valence.png`)",
        "![transition cost against valence](valence.png)",
        "",
        "Reference fans (`_core.edge_fan_mesh`, `double_cone_mesh`: a vertex in 2n tets, "
        "`vertex_fan_mesh`: the icosahedron's centre and its geodesic refinements, 20 x 4^k "
        "tets), one transition timed in a C++ loop (`_core.time_transition`, median ns). "
        "`widen`: every tet free, p at a fan tet's centroid, so (a-1) takes the proxy into "
        "that tet; the search stops there, so the figure is the mean over targets spread "
        "over the fan (max: the last). `scan`/`stay`: every tet refuses, (a-3) finds "
        "nothing, the whole fan is searched. `face`/`edge`: one free tet, p along its face "
        "(edge) and a little out of it: (a-3) picks that face (edge) after searching the "
        "whole fan.",
        "",
        markdown_table(
            _pivot(rows, "edge", edge_cases),
            [
                ("mesh", "edge fan"),
                ("valence", "tets"),
                ("widen", "widen ns"),
                ("widen_max", "widen max"),
                ("scan", "scan ns"),
                ("face", "-> FACE ns"),
            ],
        ),
        "",
        markdown_table(
            _pivot(rows, "vertex", vertex_cases),
            [
                ("mesh", "vertex fan"),
                ("valence", "tets"),
                ("widen", "widen ns"),
                ("widen_max", "widen max"),
                ("stay", "stay ns"),
                ("face", "-> FACE ns"),
                ("edge", "-> EDGE ns"),
            ],
        ),
        "",
        "Least-squares fit, ns = fixed + per tet x valence:",
        "",
        markdown_table(
            fits,
            [
                ("element", "element"),
                ("case", "case"),
                ("ns_fixed", "fixed ns"),
                ("ns_per_tet", "ns per tet"),
                ("r2", "R^2"),
            ],
        ),
        "",
        "#### The paper's open question",
        "The paper closes (section 5) with speeding up the transitions out of an edge or a "
        "vertex as future work: they search every tet that shares the element, and it "
        "proposes tetrahedralizations with fewer tets per edge and vertex. The data answers "
        f"it as follows. The cost is linear in valence (R^2 >= "
        f"{min(f['r2'] for f in fits):.3f}): a full search costs about "
        f"{per_tet('edge', 'scan')} ns per tet around an edge and "
        f"{per_tet('vertex', 'stay')} ns per tet around a vertex (three face planes, "
        "three edges and a material call per tet); a widening stops at the tet that takes "
        "the proxy, half the fan on average, so its slope is about half. At the paper's "
        "set-ups, 12 tets around an edge "
        f"and 20 around a vertex, that is {at('edge', 'scan', 12):.0f} and "
        f"{at('vertex', 'stay', 20):.0f} ns against the paper's 160 and 490 us.",
        "",
        "How much of a tick it is: on the 1 kHz press-and-slide stroke on the "
        f"sphere ({share['ticks']} point updates), {share['transitions_per_tick']:.2f} "
        f"transitions per update, of which {share['edge_per_tick']:.3f} leave an EDGE and "
        f"{share['vertex_per_tick']:.3f} a VERTEX. A proxy sliding on a face reaches an edge "
        "only where it crosses one, and a vertex only by sliding along an edge into its "
        "end, which a generic path almost never does (the paper's vertex figures come from "
        "a proxy placed on the vertex). The mesh has "
        f"{mean_e:.1f} tets per edge on average (max {share['max_tets_per_edge']}) and "
        f"{mean_v:.1f} per vertex (max {share['max_tets_per_vertex']}), so EDGE transitions "
        f"add about {share['edge_per_tick'] * edge_cost:.1f} ns per update on average by the "
        "fits above, which run on hot caches; counting instructions on the 80-face "
        "stroke (callgrind, when this generator was written) put 3 % of the proxy's work "
        "in EDGE steps on the 16 mm mesh and 9 % on a 6 mm one, whose smaller tets put "
        "more edges in the way. Either way a minority of the update: the weight of EDGE "
        "and VERTEX searches is in the worst tick, not the mean.",
        "",
        "What would cut it, in order of payoff for the work:",
        "1. **Two passes instead of one.** The engine scores every (a-3) candidate of each "
        "tet while it looks for the (a-1) tet, so a widening pays the full per-tet cost "
        "for every tet before the one that takes the proxy. Testing (a-1) first (three dot "
        "products per tet for a vertex, two for an edge) and scoring candidates only when "
        "no tet takes the proxy would cut widening to a few ns per tet scanned.",
        "2. **Material-aware fans** (done in part). A rigid tet never takes the proxy and "
        "never yields a candidate: the engine now skips it right after its (a-2) test "
        "(two or three dot products), which cut the paper's EDGE and VERTEX rows by half "
        "to two thirds in the benchmark, whose set-ups use rigid tets (docs/benchmarks.md). "
        "The set-ups "
        "here use a drag material that refuses every move, so they still measure the "
        "full search. Storing per edge and vertex only the entries that can move would "
        "skip reading the rigid tets' planes as well.",
        "3. **Start where the proxy came from.** The tets around a vertex form a spherical "
        "triangulation of directions; walking it from the tet the proxy arrived through "
        "toward p - q finds the (a-1) tet in about sqrt(n) steps instead of n/2 on average.",
        "4. **Fewer tets per element** (the paper's proposal) pays least: well-shaped tets "
        "need about 20 or more around a vertex (4 pi over a regular tet's 0.55 sr corner is "
        "about 23) and about 5 around an edge (360 over 70.5 degrees), which is where "
        "fTetWild's means already are. Only the worst vertices (about twice the mean) could "
        "gain, by about 2x, at the price of a constrained mesher.",
        "",
    ]
    return lines


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
    quick: bool,
    elapsed_s: float,
) -> None:
    lines = [
        "# Evaluation: where the tetrahedral proxy is fast, accurate, and where others break",
        "",
        f"Regenerate everything with `{COMMAND}` (this run: {elapsed_s:.0f} s on 2 cores, "
        "building first any mesh not in `cache/`; `--quick` for the reduced run the tests "
        "use). Times are wall "
        "clock on the machine that ran it, shared with other work: read them as ratios, "
        "not as absolutes. Built meshes are cached in `cache/` (fTetWild's output varies "
        "between runs).",
        "" if not quick else "\n**This is a --quick run: fewer models, shorter walks.**\n",
        "![speed against accuracy](speed_vs_error.png)",
        "",
        "## Targets of issue 4, as measured",
        *targets(accuracy_rows, stability_rows),
        *example_shading.target_line(list(shading_rows), list(example_rows)),
        "",
        *speed_gap(accuracy_rows),
        "## Methods",
        f"- **{methods.TET}**: the engine (ALGORITHM.md), whole space in tets.",
        f"- **{methods.SHADED}**: the same proxy; the force's normal component takes the "
        "normal interpolated from vertex normals at the shaded contact point (Morgenbesser "
        "and Srinivasan; beyond the paper), the normals fitted to the source surface at the "
        "scale of the rigid surface's facets. `core/src/force_shading.cpp`.",
        f"- **{methods.GOD}**: Zilles and Salisbury on the source triangles, up to 3 "
        "constraint planes, Lagrange solve, AABB tree. `core/src/baselines/god_object.cpp`.",
        f"- **{methods.VOXEL}**: the method the paper replaces: cells of the true sphere "
        "(centre inside), a god-object kept in free cells by a 3D DDA, axis-aligned "
        "constraint planes. `core/src/baselines/voxel_proxy.cpp`. Pressed deeper than a "
        "cell, its proxy is caught in the concave corners of the staircase (a local minimum "
        "of |q - p| over free cells) and lags behind the slide: its large direction errors "
        "are that trap, not noise.",
        *scene_sizing(accuracy_rows),
        "",
        "## Accuracy and speed (sphere r = 30 mm, press 5 mm, slide at 100 mm/s, 8 strokes)",
        "Direction error: angle between the force and the true normal p/|p|. Position error: "
        "||q| - R|. Penetration: max(R - |q|) into the true sphere (facets and stairs lie "
        "inside it). Memory: the model the method queries (mesh + tree, surface + tree, grid).",
        "",
        markdown_table(
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
        "",
        "### Lag inside drag material (D = 1 mm)",
        markdown_table(
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
        "",
        "The baselines have no penetrable material, so no lag figures.",
        "",
        "## Stability: method x scenario",
        "A verdict fails on NaN, on a proxy deeper in the true rigid region than the method's "
        "resolution allows (the figure's `allowed`), on a proxy beyond the wall's mid-plane, "
        "or on a failed engine invariant (tet proxy only).",
        "",
        markdown_table(
            stability_rows,
            [
                ("scenario", "scenario"),
                ("method", "method"),
                ("verdict", "verdict"),
                ("ticks", "ticks"),
                ("figure", "figure"),
            ],
        ),
        "",
        "### Closed loop with the simulated hand",
        "A 0.1 kg hand with 2 N s/m damping, held by a 0.3 N/mm grip to a scripted stroke "
        "(press 5 mm, slide, hold, withdraw) on the sphere, 1 kHz, semi-implicit Euler. "
        "Energy gained: work of the rendered force on the hand over the stroke (> 0: the loop "
        "gave energy). Fails on chatter (force ripple during the hold > 5 % and > 0.01 N) or "
        "on energy gained > 1 % of 0.5 k (5 mm)^2.",
        "",
        markdown_table(
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
        "",
        "## Mesh economy",
        "Tets, fTetWild build time and tick time against force error (tet proxy, 1 kHz "
        "stroke) for the 320-face sphere with uniform and adaptive air sizing, and with a "
        "bounding tet instead of the cube as the enclosure.",
        "",
        markdown_table(
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
        "",
        *sphere_sizing_note(economy_rows),
        *example_shading.section(list(shading_rows)),
        *example_section(list(example_rows)),
        *valence_section(valence_rows, valence_fit, valence_share),
        "## Files",
        "`accuracy.csv`, `drag_lag.csv`, `stability.csv`, `closed_loop.csv`, "
        "`mesh_economy.csv`, `example_economy.csv`, `example_shading.csv`, `valence.csv`, "
        "`speed_vs_error.png`, "
        "`valence.png`.",
        "",
    ]
    (out / "README.md").write_text("\n".join(lines))
