"""Rebuild the example scenes in examples/ from their surface meshes.

    python examples/build_examples.py            # all of them
    python examples/build_examples.py sphere80   # one

- sphere80, sphere320: the paper's spheres (80 and 320 faces, radius 30 mm, rigid) in a cube,
  as in its Table 3 (394 and 1917 tets).
- mouse: the Stanford bunny standing in for the paper's scanned mouse (about 12k tets, about
  120 mm long); the source is pymeshlab's sample bunny10k_textured.obj (109 boundary edges in
  5 holes, closed by the repair step), read from the installed pymeshlab.
- finger: a layered finger, 80 mm long: skin (membrane) over flesh (drag) over three bones
  (rigid); its surfaces are generated here and written to examples/meshes/.

fTetWild's output differs between runs, so the committed .hapticut.msgpack files are one
build; `hapticut info examples/<name>.hapticut.msgpack` prints what it holds.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from hapticut.scenebuild import BuildSettings, Region, build
from hapticut.scenefile import BladeSpec, Material, save_scene

HERE = Path(__file__).resolve().parent
MESHES = HERE / "meshes"
SPHERE_RADIUS_MM = 30.0
MOUSE_LENGTH_MM = 120.0
# The paper's blade: a 0.1 m edge sampled by 50 points; here centred on the tool origin.
SCALPEL = BladeSpec("scalpel", (-50.0, 0.0, 0.0), (50.0, 0.0, 0.0), 50)
RIGID = Material("body", "rigid")


def icosphere(radius_mm: float, subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """An icosahedron subdivided (80 faces: 1, 320: 2), on a sphere of the radius. pymeshlab's,
    not hapticut.shapes.icosphere (the same mesh, rotated): the committed spheres were built
    from this one, the evaluation measures them against it, and fTetWild meshes the rotated
    one differently (about 308 tets for sphere80 against 338)."""
    import pymeshlab

    meshes = pymeshlab.MeshSet()
    meshes.create_sphere(radius=radius_mm, subdiv=subdivisions)
    mesh = meshes.current_mesh()
    return mesh.vertex_matrix(), mesh.face_matrix()


def revolve(xs, radii, segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A closed surface of revolution about the x axis: rings at xs with radii, capped by a
    pole at each end (radius 0 there). Outward oriented."""
    xs, radii = np.asarray(xs, float), np.asarray(radii, float)
    angles = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    rings = [
        np.column_stack([np.full(segments, x), r * np.cos(angles), r * np.sin(angles)])
        for x, r in zip(xs[1:-1], radii[1:-1], strict=True)
    ]
    vertices = np.vstack([[[xs[0], 0, 0]], *rings, [[xs[-1], 0, 0]]])
    faces = []
    last = len(vertices) - 1
    for j in range(segments):
        k = (j + 1) % segments
        faces.append([0, 1 + k, 1 + j])
        base = 1 + (len(rings) - 1) * segments
        faces.append([last, base + j, base + k])
    for i in range(len(rings) - 1):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            k = (j + 1) % segments
            faces.append([a + j, a + k, b + k])
            faces.append([a + j, b + k, b + j])
    return vertices, np.array(faces)


def capsule(x0: float, x1: float, radius: float, segments: int = 24, cap_rings: int = 6):
    """A capsule along x from x0 to x1 (ends included) of the given radius."""
    theta = np.linspace(0, np.pi / 2, cap_rings + 1)
    left_x = x0 + radius * (1 - np.cos(theta))
    left_r = radius * np.sin(theta)
    body = np.linspace(x0 + radius, x1 - radius, max(2, int((x1 - x0 - 2 * radius) / radius) + 1))
    xs = np.concatenate([left_x, body[1:-1], (x0 + x1 - left_x)[::-1]])
    rs = np.concatenate([left_r, np.full(len(body) - 2, radius), left_r[::-1]])
    return revolve(xs, rs, segments)


def finger_profile(inset_mm: float, segments: int = 32):
    """The finger's outer surface, 80 mm along x, 9 mm radius tapering to 7.5 mm at the tip,
    shrunk by inset_mm (the skin's thickness)."""
    theta = np.linspace(0, np.pi / 2, 9)
    base_r, tip_r = 9.0 - inset_mm, 7.5 - inset_mm
    x0, x1 = -40.0 + inset_mm, 40.0 - inset_mm
    left_x, left_r = x0 + base_r * (1 - np.cos(theta)), base_r * np.sin(theta)
    right_x, right_r = x1 - tip_r * (1 - np.cos(theta[::-1])), tip_r * np.sin(theta[::-1])
    body_x = np.linspace(x0 + base_r, x1 - tip_r, 12)[1:-1]
    body_r = np.interp(body_x, [x0 + base_r, x1 - tip_r], [base_r, tip_r])
    return revolve(
        np.concatenate([left_x, body_x, right_x]),
        np.concatenate([left_r, body_r, right_r]),
        segments,
    )


def write_obj(path: Path, vertices, faces) -> None:
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def finger_meshes() -> dict[str, Path]:
    """Write the finger's surfaces to examples/meshes/ and return their paths."""
    MESHES.mkdir(exist_ok=True)
    shapes = {
        "finger_skin": finger_profile(0.0),
        "finger_flesh": finger_profile(1.5),
        "finger_bone_proximal": capsule(-36.0, -9.0, 3.5),
        "finger_bone_middle": capsule(-7.0, 12.0, 3.2),
        "finger_bone_distal": capsule(14.0, 30.0, 2.8),
    }
    paths = {}
    for name, (vertices, faces) in shapes.items():
        paths[name] = MESHES / f"{name}.obj"
        write_obj(paths[name], vertices, faces)
    return paths


def bunny_source() -> Path:
    import pymeshlab

    return Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny10k_textured.obj"


def mouse_region() -> Region:
    """The bunny, scaled to 120 mm along its longest side and centred on the origin."""
    region = Region.from_file(bunny_source(), Material("body", "rigid"), name="mouse")
    low, high = region.vertices.min(axis=0), region.vertices.max(axis=0)
    scale = MOUSE_LENGTH_MM / float((high - low).max())
    return replace(region, vertices=(region.vertices - (low + high) / 2) * scale)


def example_sphere(faces: int):
    subdivisions = {80: 1, 320: 2}[faces]
    region = Region(f"sphere{faces}", *icosphere(SPHERE_RADIUS_MM, subdivisions), RIGID)
    # The paper's sphere keeps every face; sizing by default (the faces' own edge length near
    # the surface, 4x that far away), coarsened as far as fTetWild's quality allows.
    settings = BuildSettings(enclosure="cube", simplify=False, coarsen=True, accuracy_mm=0.3)
    return [region], settings, {"paper_model": f"sphere{faces}"}


def example_mouse():
    # 2.6 mm accuracy: the 10k-face scan is simplified to about 1.5k-2k faces (1 mm) and meshed
    # within a 1 mm envelope, which lands near the paper's 12k tets.
    settings = BuildSettings(enclosure="cube", accuracy_mm=2.6, margin_mm=20.0, edge_far_mm=40.0)
    return [mouse_region()], settings, {"paper_model": "mouse", "source": "bunny10k_textured.obj"}


def example_finger():
    paths = finger_meshes()
    skin = Material("skin", "membrane", break_force_N=1.0)
    flesh = Material("flesh", "drag", drag_distance_mm=1.0)
    bone = Material("bone", "rigid")
    regions = [
        Region.from_file(paths["finger_skin"], skin),
        Region.from_file(paths["finger_flesh"], flesh),
        *(
            Region.from_file(paths[f"finger_bone_{b}"], bone)
            for b in ("proximal", "middle", "distal")
        ),
    ]
    # The skin is 1.5 mm thick: a 0.5 mm accuracy (0.25 mm envelope) keeps its two surfaces
    # apart; fTetWild conforms to both, so 2.5 mm edges near the surfaces suffice.
    settings = BuildSettings(enclosure="box", accuracy_mm=0.5, edge_near_mm=2.5, edge_far_mm=12.0)
    return regions, settings, {"layers": "skin (membrane) / flesh (drag) / bone (rigid)"}


EXAMPLES = {
    "sphere80": lambda: example_sphere(80),
    "sphere320": lambda: example_sphere(320),
    "mouse": example_mouse,
    "finger": example_finger,
}


def output_path(name: str) -> Path:
    return HERE / f"{name}.hapticut.msgpack"


def build_example(name: str, settings_override: dict | None = None):
    """(scene, seconds) of one example; settings_override replaces BuildSettings fields."""
    regions, settings, info = EXAMPLES[name]()
    if settings_override:
        settings = replace(settings, **settings_override)
    start = time.perf_counter()
    scene = build(regions, blades=[SCALPEL], settings=settings)
    seconds = time.perf_counter() - start
    scene.metadata["example"] = {
        "name": name,
        "rebuild": "python examples/build_examples.py " + name,
        **info,
    }
    return scene, seconds


def main(names: list[str]) -> int:
    for name in names or list(EXAMPLES):
        if name not in EXAMPLES:
            print(f"unknown example {name!r}; examples: {', '.join(EXAMPLES)}", file=sys.stderr)
            return 2
        scene, seconds = build_example(name)
        save_scene(scene, output_path(name))
        counts = scene.metadata["build_report"]["tets_per_material"]
        path = output_path(name)
        print(f"{name}: {len(scene.tets)} tets {counts} in {seconds:.1f} s -> {path.name}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
