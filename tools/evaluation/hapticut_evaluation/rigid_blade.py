"""The rigid blade against the paper's independent points (docs/decisions.md, "The rigid blade").

- Stiffness felt against the length of edge over bone: a 50-point blade (2 mm spacing) pressed
  into a flat bone under n of its points, n = 1, 2, 5, 10, 25, 50. Independent points push back
  with the n points the bone holds; a rigid blade with all of its springs, n k at every n.
- Penetration of the ideal edge: strokes across the finger example's bones, a cylinder and a
  plate thinner than the point spacing, the ideal edge sampled at ten times the point density
  (independent points: the polyline through them); every sample inside rigid material counts.
- Force shading on the example spheres: a 1-point and a 50-point rigid blade on the
  press-and-slide strokes of the shaded independent points' evaluation (example_shading.py),
  the force's direction error with shading off and on.
"""

from __future__ import annotations

import numpy as np
from hapticut import _core, engine

K = 0.1  # N/mm, the scenes' default stiffness.
POINTS = 50
SPACING_MM = 2.0
PRESS_MM = 2.0  # Into the bone, where the stiffness is read.
CONTACT_POINTS = (1, 2, 5, 10, 25, 50)
SAMPLES_PER_SPACING = 10
SPEED_MM_S = 100.0
FREE = {"name": "air", "model": "free"}
RIGID = {"name": "bone", "model": "rigid"}
COUPLINGS = (("independent", "free"), ("rigid", "free"), ("rigid", "locked"))


def _label(coupling: str, orientation: str) -> str:
    return "independent points" if coupling == "independent" else f"rigid, {orientation}"


def _blade(space, coupling: str, orientation: str, half_mm: float, points: int):
    return _core.Blade(
        space, [-half_mm, 0, 0], [half_mm, 0, 0], points,
        coupling=coupling, orientation=orientation,
    )  # fmt: skip


def slab_space(contact_points: int) -> tuple[_core.Space, float]:
    """Air over a bone slab (top at z = 0) that lies under the middle `contact_points` of a
    50-point blade along x centred at x = 0, with 1 mm of air to the next points; the slab's
    top height."""
    half = SPACING_MM * (POINTS - 1) / 2
    first = (POINTS - contact_points) // 2
    x0 = -half + first * SPACING_MM - SPACING_MM / 2
    x1 = x0 + contact_points * SPACING_MM
    xs = np.unique(np.concatenate([np.arange(-half - 4, half + 4.01, 1.0), [x0, x1]]))
    ys = np.arange(-4.0, 4.01, 2.0)
    zs = np.arange(-8.0, 8.01, 1.0)
    vertices, tets = _core.grid_mesh(xs, ys, zs)
    c = vertices[tets].mean(axis=1)
    bone = (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 2] < 0)
    return _core.Space(vertices, tets, bone.astype(np.int32), [FREE, RIGID]), 0.0


def run_stiffness_vs_contact(contacts=CONTACT_POINTS) -> list[dict]:
    """One row per bone length: the stiffness each coupling renders, pressed PRESS_MM in."""
    half = SPACING_MM * (POINTS - 1) / 2
    rows = []
    for n in contacts:
        space, top = slab_space(n)
        row = {"points_over_bone": n, "n_k_N_per_mm": n * K, "blade_k_N_per_mm": POINTS * K}
        for coupling, orientation in COUPLINGS:
            blade = _blade(space, coupling, orientation, half, POINTS)
            poses = engine.straight_stroke([0, 0, top + 4], [0, 0, top - PRESS_MM], SPEED_MM_S)
            blade.reset(poses[0])
            blade.run(poses, 0.001)
            tick = blade.step(poses[-1], 0.001)
            key = _label(coupling, orientation).replace(", ", "_").replace(" ", "_")
            row[f"{key}_N_per_mm"] = float(tick["force_N"][2]) / PRESS_MM
        rows.append(row)
    return rows


def _edge_samples(q: np.ndarray, coupling: str) -> np.ndarray:
    """The ideal edge at SAMPLES_PER_SPACING samples per point spacing: a rigid blade's
    straight edge between its end points, independent points' polyline through them."""
    t = np.linspace(0.0, 1.0, SAMPLES_PER_SPACING, endpoint=False)
    if coupling == "rigid":
        t = np.linspace(0.0, 1.0, SAMPLES_PER_SPACING * (len(q) - 1) + 1)
        return q[0] + t[:, None] * (q[-1] - q[0])
    segments = q[:-1, None, :] + t[None, :, None] * (q[1:] - q[:-1])[:, None, :]
    return np.vstack([segments.reshape(-1, 3), q[-1:]])


FACES_OF_TET = ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2))
ON_SURFACE_MM = 1e-6  # Samples this close to the bone's surface touch it: not inside.


def bone_surface(space, rigid_tets: np.ndarray) -> np.ndarray:
    """(F, 3, 3): the triangles between rigid tets and the rest (or the mesh's outside)."""
    tets = np.asarray(space.tets)
    faces = np.sort(tets[:, FACES_OF_TET].reshape(-1, 3), axis=1)
    owner_rigid = np.repeat(rigid_tets, 4)
    _, inverse, counts = np.unique(faces, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    rigid_sides = np.bincount(inverse, weights=owner_rigid.astype(float))
    # A face on the bone's surface has exactly one rigid side.
    surface = (rigid_sides[inverse] == 1) & owner_rigid
    del counts
    return np.asarray(space.vertices)[faces[surface]]


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def depth_in_bone(point: np.ndarray, triangles: np.ndarray) -> float:
    """The distance from a point in bone to the bone's surface (point-triangle distances)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    d = np.einsum("ij,ij->i", point - a, n)
    foot = point - d[:, None] * n
    inside = np.ones(len(triangles), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, foot - u), n) >= 0
    p = np.broadcast_to(point, a.shape)
    edges = np.minimum.reduce([_segment_distance(p, a, b), _segment_distance(p, b, c),
                               _segment_distance(p, c, a)])  # fmt: skip
    return float(np.min(np.where(inside, np.abs(d), edges)))


def _penetration(space, rigid_tets, strokes, half_mm, points) -> list[dict]:
    surface = bone_surface(space, rigid_tets)
    rows = []
    for coupling, orientation in COUPLINGS:
        ticks = inside_ticks = inside_samples = samples_total = 0
        deepest = 0.0
        for poses in strokes:
            blade = _blade(space, coupling, orientation, half_mm, points)
            blade.reset(poses[0])
            for pose in poses:
                blade.step(pose, 0.001)
                samples = _edge_samples(np.asarray(blade.q), coupling)
                tets = space.locate(np.ascontiguousarray(samples))
                located = samples[(tets >= 0) & rigid_tets[np.maximum(tets, 0)]]
                depths = [depth_in_bone(x, surface) for x in located]
                inside = sum(d > ON_SURFACE_MM for d in depths)
                deepest = max([deepest, *depths])
                ticks += 1
                samples_total += len(samples)
                inside_samples += inside
                inside_ticks += inside > 0
        rows.append(
            {
                "method": _label(coupling, orientation),
                "strokes": len(strokes),
                "ticks": ticks,
                "ticks_with_edge_in_bone": inside_ticks,
                "edge_samples": samples_total,
                "edge_samples_in_bone": inside_samples,
                "deepest_mm": round(deepest, 4),
            }
        )
    return rows


def _press_and_slide(x: float, y0: float, y1: float, z_top: float, z_low: float) -> np.ndarray:
    down = engine.straight_stroke([x, y0, z_top], [x, y0, z_low], SPEED_MM_S)
    across = engine.straight_stroke([x, y0, z_low], [x, y1, z_low], SPEED_MM_S)
    return np.vstack([down, across[1:]])


def cylinder_space(radius_mm: float = 4.0) -> _core.Space:
    """A bone cylinder along y (axis at x = z = 0) in air, 1 mm cells."""
    xs = np.arange(-30.0, 30.01, 1.0)
    ys = np.arange(-6.0, 6.01, 2.0)
    zs = np.arange(-8.0, 10.01, 1.0)
    vertices, tets = _core.grid_mesh(xs, ys, zs)
    c = vertices[tets].mean(axis=1)
    bone = np.hypot(c[:, 0], c[:, 2]) < radius_mm
    return _core.Space(vertices, tets, bone.astype(np.int32), [FREE, RIGID])


def plate_space(thickness_mm: float = 0.5) -> _core.Space:
    """A bone plate thinner than the point spacing, edge-on under the blade: x in
    [-t/2, t/2], top at z = 0."""
    xs = np.unique(np.concatenate([np.arange(-30.0, 30.01, 1.0), [-thickness_mm / 2,
                                                                   thickness_mm / 2]]))  # fmt: skip
    ys = np.arange(-6.0, 6.01, 2.0)
    zs = np.arange(-8.0, 8.01, 1.0)
    vertices, tets = _core.grid_mesh(xs, ys, zs)
    c = vertices[tets].mean(axis=1)
    bone = (np.abs(c[:, 0]) < thickness_mm / 2) & (c[:, 2] < 0)
    return _core.Space(vertices, tets, bone.astype(np.int32), [FREE, RIGID])


def run_edge_penetration(finger_path, *, quick: bool = False) -> list[dict]:
    """Rows per scene and coupling: ticks and edge samples with any part of the ideal edge
    inside bone. The blades: 20 points on 40 mm (the demo's knife is 40 on 40 mm; 2.1 mm
    spacing, as the 50-point, 100 mm blade of the paper)."""
    rows = []
    # The finger: a 40 mm blade along its bones, pressed 3 mm under their axis and slid
    # sideways off them, at several places along the finger (the joints among them).
    scene, space = engine.load_space(finger_path)
    names = [m.model for m in scene.materials]
    rigid = np.array([names[i] == "rigid" for i in space.tet_materials])
    places = (-22.0, 2.0) if quick else (-30.0, -22.0, -9.0, 2.0, 12.0, 22.0, 32.0)
    strokes = [_press_and_slide(x, 0.0, 18.0, 15.0, -3.0) for x in places]
    for row in _penetration(space, rigid, strokes, 20.0, 20):
        rows.append({"scene": "finger (its bones)", **row})
    # A cylinder across the blade (independent points wrap round it); a plate thinner than
    # the spacing, edge-on, under a point and between two (independent points pass it).
    for name, space, offsets, quick_offsets, start_z in (
        ("cylinder r 4 mm across the edge", cylinder_space(), (0.0, 3.0, 7.5), (0.0,), 8.0),
        ("plate 0.5 mm, edge-on", plate_space(), (0.0, 0.5, 1.05), (1.05,), 4.0),
    ):
        rigid = np.asarray(space.tet_materials) == 1
        places = quick_offsets if quick else offsets
        strokes = [_press_and_slide(x, 0.0, 4.0, start_z, -3.0) for x in places]
        for row in _penetration(space, rigid, strokes, 20.0, 20):
            rows.append({"scene": name, **row})
    return rows


# The example spheres' force shading: the strokes of example_shading.py, the blade's
# middle on each stroke's point, its edge across the slide on the sphere's tangent.
SHADING_SCENES = ("sphere80", "sphere320")
SHADING_POINTS = (1, 50)
SHADING_BLADE_MM = 40.0


def _turn_from_x(direction: np.ndarray) -> np.ndarray:
    """The least turn (w, x, y, z) taking +x onto the unit `direction`."""
    q = np.array([1.0 + direction[0], 0.0, -direction[2], direction[1]])
    if q[0] < 1e-9:  # Opposite: half a turn about z.
        return np.array([0.0, 0.0, 0.0, 1.0])
    return q / np.linalg.norm(q)


def stroke_poses(source, stroke: np.ndarray, slide: np.ndarray) -> np.ndarray:
    """(ticks, 7) poses of a blade along the tool's x whose middle follows `stroke` (ticks,
    3), its edge across the slide (the `slide` ticks' steps) and along the surface's
    tangent; the press before the slide holds the slide's first direction."""
    _, tri, bary = source.closest(stroke)
    normal = source.smooth_normal(tri, bary)
    step = np.diff(stroke, axis=0, append=stroke[-1:])
    step -= normal * np.einsum("ij,ij->i", step, normal)[:, None]
    moving = slide & (np.linalg.norm(step, axis=1) > 1e-9)
    direction = step[int(np.argmax(moving))] if moving.any() else np.cross(normal[0], [0, 0, 1.0])
    poses = np.zeros((len(stroke), 7))
    for k in range(len(stroke)):
        if moving[k]:
            direction = step[k]
        edge = np.cross(normal[k], direction)
        edge /= np.linalg.norm(edge)
        poses[k, :3] = stroke[k]
        poses[k, 3:] = _turn_from_x(edge)
    return poses


def _shading_run(space, source, path: np.ndarray, slide: np.ndarray, points: int, shaded: bool):
    """Every stroke of `path` (ticks, strokes, 3) with a fresh rigid blade: the ideal edge's
    middle and the force per tick, each (ticks, strokes, 3), and the slide's ticks whose
    rounds ended short of the constrained optimum (unresolved: the pose lags the device)."""
    half = SHADING_BLADE_MM / 2 if points > 1 else 0.0
    middles = np.zeros_like(path)
    forces = np.zeros_like(path)
    unresolved = 0
    for s in range(path.shape[1]):
        blade = _core.Blade(space, [-half, 0, 0], [half, 0, 0], points, coupling="rigid")
        settings = blade.settings
        settings.force_shading = shaded
        blade.settings = settings
        poses = stroke_poses(source, path[:, s], slide)
        blade.reset(poses[0])
        for k, pose in enumerate(poses):
            tick = blade.step(pose, 0.001)
            forces[k, s] = tick["force_N"]
            unresolved += bool(slide[k] and tick["unresolved"])
            q = np.asarray(blade.q)
            middles[k, s] = (q[0] + q[-1]) / 2
    return middles, forces, unresolved


def run_sphere_shading(scenes=SHADING_SCENES, points=SHADING_POINTS, *, log=print) -> list[dict]:
    """One row per example sphere and blade: the direction error of the rigid blade's force
    against the source sphere's smooth normal at the closest source point to the ideal edge's
    middle, plain and shaded (from the scene's own rigid surface, what a servo has), on the
    strokes of the shaded independent points (example_shading.run_example_shading)."""
    from hapticut_evaluation import example_shading, surface

    rows = []
    for name, space, source, path, slide in example_shading.example_strokes(
        scenes, example_shading.STROKES, log
    ):
        for count in points:
            row = {"example": name, "points": count}
            for kind, shaded in (("plain", False), ("shaded", True)):
                middles, forces, unresolved = _shading_run(
                    space, source, path, slide, count, shaded
                )
                m = surface.contact_metrics(source, slide, middles, forces)
                row[f"{kind}_dir_err_smooth_mean_deg"] = m["dir_err_smooth_mean_deg"]
                row[f"{kind}_dir_err_smooth_p95_deg"] = m["dir_err_smooth_p95_deg"]
            # Shading changes the force, not the pose: one count for both.
            row["contact_updates"] = m["contact_updates"]
            row["unresolved_ticks"] = unresolved
            rows.append(row)
            log(
                f"  {name:9s} rigid blade of {count:2d} points: smooth error plain "
                f"{row['plain_dir_err_smooth_mean_deg']:.3f}, shaded "
                f"{row['shaded_dir_err_smooth_mean_deg']:.3f} deg"
            )
    return rows
