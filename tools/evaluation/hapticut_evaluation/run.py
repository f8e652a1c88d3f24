"""Run the whole evaluation and write it to a folder."""

from __future__ import annotations

import time
from pathlib import Path

from hapticut_evaluation import (
    accuracy,
    charts,
    cut_memory,
    economy,
    example_shading,
    report,
    rigid_blade,
    stability,
    valence,
)


def run_stability(cache: Path, *, quick: bool, families=None, log=print) -> list[dict]:
    rows = []
    for scenario in stability.stability_scenarios(cache, quick=quick):
        for row in stability.evaluate_scenario(scenario, families):
            rows.append(row)
            log(f"  {row['scenario'][:40]:40s} {row['method']:30s} {row['verdict']}")
    return rows


def run_all(out: Path, *, quick: bool = False, log=print) -> dict:
    start = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    cache = out / "cache"
    log("accuracy and speed")
    faces = (80, 320) if quick else accuracy.SPHERE_FACES
    voxel_sizes = (4.0, 1.0) if quick else None
    accuracy_rows = accuracy.run_accuracy(
        cache,
        faces=faces,
        min_seconds=0.0 if quick else accuracy.TIMING_MIN_S,
        log=log,
        **({"voxel_sizes": voxel_sizes} if voxel_sizes else {}),
    )
    drag_rows = accuracy.run_drag_lag(cache, faces=80 if quick else 320)
    log("stability")
    stability_rows = run_stability(cache, quick=quick, log=log)
    log("closed loop")
    loop_rows = stability.run_closed_loop(cache, quick=quick)
    log("valence")
    valence_rows = valence.run_valence(quick=quick)
    valence_fit = valence.fit(valence_rows)
    valence_share = valence.transition_share(cache, faces=80 if quick else 320)
    charts.valence(valence_rows, out / "valence.png")
    log("mesh economy")
    economy_rows = economy.sizing_economy(cache, quick=quick, log=log)
    example_rows = economy.example_economy(cache, quick=quick, log=log)
    log("force shading on the example scenes")
    shading_rows = example_shading.run_example_shading(quick=quick, log=log)
    log("force shading of the rigid blade on the example spheres")
    blade_shading_rows = rigid_blade.run_sphere_shading(log=log)
    log("the rigid blade")
    rigid_rows = rigid_blade.run_stiffness_vs_contact()
    penetration_rows = rigid_blade.run_edge_penetration(
        economy.EXAMPLES_DIR / "finger.hapticut.msgpack", quick=quick
    )
    charts.rigid_stiffness(rigid_rows, out / "rigid_stiffness.png")
    log("cut memory")
    slits, presses = cut_memory.slit_passes(), cut_memory.skin_passes()
    cut_memory_rows = cut_memory.run_cut_memory(slits, presses)
    charts.cut_memory(slits, presses, out / "cut_memory.png")
    for name, rows in [
        ("rigid_blade", rigid_rows),
        ("edge_penetration", penetration_rows),
        ("accuracy", accuracy_rows),
        ("drag_lag", drag_rows),
        ("stability", stability_rows),
        ("closed_loop", loop_rows),
        ("valence", valence_rows),
        ("mesh_economy", economy_rows),
        ("example_economy", example_rows),
        ("example_shading", shading_rows),
        ("rigid_blade_shading", blade_shading_rows),
        ("cut_memory", cut_memory_rows),
    ]:
        report.write_csv(out / f"{name}.csv", rows)
    charts.speed_vs_error(accuracy_rows, out / "speed_vs_error.png")
    report.write_page(
        out,
        accuracy_rows=accuracy_rows,
        drag_rows=drag_rows,
        stability_rows=stability_rows,
        loop_rows=loop_rows,
        valence_rows=valence_rows,
        valence_fit=valence_fit,
        valence_share=valence_share,
        economy_rows=economy_rows,
        example_rows=example_rows,
        shading_rows=shading_rows,
        blade_shading_rows=blade_shading_rows,
        rigid_rows=rigid_rows,
        penetration_rows=penetration_rows,
        cut_memory_rows=cut_memory_rows,
        quick=quick,
        elapsed_s=time.perf_counter() - start,
    )
    log(f"wrote {out} in {time.perf_counter() - start:.0f} s")
    return {"accuracy": accuracy_rows, "stability": stability_rows, "closed_loop": loop_rows}
