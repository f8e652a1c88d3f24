"""Surface meshes for scene building: reading, checking, repairing (pymeshlab), measuring
(simplifying: simplify.py).

Every problem that cannot be repaired raises BuildError naming the region and the problem;
every repair is counted in the region's report (a dict of counts, zero entries left out).
"""

from __future__ import annotations

import os

import numpy as np

from . import forked
from .errors import BuildError
from .forked import Beside
from .geometry import Surface, signed_volume, triangle_areas

# Faces with area below this fraction of (mean edge length)^2 count as zero-area (degenerate).
DEGENERATE_AREA_RATIO = 1e-12
# A region whose volume is below this fraction of its bounding box's volume encloses nothing.
MIN_VOLUME_RATIO = 1e-9


def _meshlab():
    try:
        import pymeshlab
    except ImportError:  # pragma: no cover - the "build" extra brings it
        raise ImportError("scene building needs pymeshlab: pip install 'hapticut[build]'") from None
    return pymeshlab


# ---------------------------------------------------------------------------------------------
# Reading


def read_obj(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a Wavefront OBJ file, with non-finite coordinates kept.

    Polygons are fanned into triangles; texture and normal indices are ignored; negative
    (relative) indices are resolved. pymeshlab drops NaN vertices silently, so OBJ is read
    here to let the checks name them.
    """
    vertices: list[list[float]] = []
    faces: list[list[int]] = []
    with open(path, "rb") as file:
        for number, raw in enumerate(file, start=1):
            line = raw.split(b"#", 1)[0].strip()
            if not line:
                continue
            words = line.split()
            try:
                if words[0] == b"v":
                    vertices.append([float(w) for w in words[1:4]])
                    if len(vertices[-1]) != 3:
                        raise ValueError("a vertex needs 3 coordinates")
                elif words[0] == b"f":
                    corners = [int(w.split(b"/")[0]) for w in words[1:]]
                    if len(corners) < 3:
                        raise ValueError("a face needs at least 3 corners")
                    corners = [c - 1 if c > 0 else len(vertices) + c for c in corners]
                    faces.extend(
                        [corners[0], corners[i], corners[i + 1]] for i in range(1, len(corners) - 1)
                    )
            except (ValueError, IndexError) as error:
                raise BuildError("", f"{path}: line {number} is not valid OBJ ({error})") from None
    return (
        np.array(vertices, dtype=np.float64).reshape(-1, 3),
        np.array(faces, dtype=np.int64).reshape(-1, 3),
    )


def read_surface(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) and triangles (f, 3) of a surface mesh file (OBJ, PLY, STL, OFF, ...).

    Raises BuildError for a file that is missing or is not a mesh.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise BuildError("", f"{path}: no such file")
    if path.lower().endswith(".obj"):
        vertices, faces = read_obj(path)
    else:
        if path.lower().endswith(".stl"):
            _check_stl_size(path)
        pymeshlab = _meshlab()
        meshes = pymeshlab.MeshSet()
        try:
            meshes.load_new_mesh(path)
        except pymeshlab.PyMeshLabException as error:
            detail = str(error).strip().splitlines()[-1]
            raise BuildError("", f"{path}: not a mesh pymeshlab can read ({detail})") from None
        mesh = meshes.current_mesh()
        vertices, faces = mesh.vertex_matrix(), mesh.face_matrix()
    if len(vertices) == 0 and len(faces) == 0:
        raise BuildError("", f"{path}: not a mesh (no vertices and no faces)")
    return vertices, faces


def _check_stl_size(path: str) -> None:
    """A binary STL's size must match its triangle count (pymeshlab hangs on some garbage)."""
    with open(path, "rb") as file:
        head = file.read(84)
    if head[:5].lower() == b"solid":
        return  # ASCII STL (or binary with a misleading header: the size check below decides).
    size = os.path.getsize(path)
    if len(head) < 84 or size != 84 + 50 * int.from_bytes(head[80:84], "little"):
        raise BuildError(
            "", f"{path}: not a mesh (not ASCII STL, and not a binary STL of its size)"
        )


# ---------------------------------------------------------------------------------------------
# Checks and repairs


def check_arrays(region: str, vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """The arrays as float64 (n, 3) and int32 (f, 3); BuildError for empty, NaN or bad indices."""
    try:
        vertices = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces)
    except (TypeError, ValueError) as error:
        raise BuildError(region, f"vertices or faces are not numeric arrays ({error})") from None
    if vertices.size == 0 or faces.size == 0:
        raise BuildError(region, "empty mesh (no vertices or no faces)")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise BuildError(region, f"vertices must have shape (n, 3), not {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise BuildError(region, f"faces must be triangles, shape (f, 3), not {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        if not np.all(np.isfinite(faces)) or np.any(faces != np.round(faces)):
            raise BuildError(region, "face indices must be integers")
        faces = faces.astype(np.int64)
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        first = int(np.argmax(bad))
        raise BuildError(
            region,
            f"{int(bad.sum())} vertices have coordinates that are not finite numbers "
            f"(first: vertex {first} = {vertices[first].tolist()})",
        )
    out_of_range = (faces < 0) | (faces >= len(vertices))
    if out_of_range.any():
        row = int(np.argmax(out_of_range.any(axis=1)))
        raise BuildError(
            region, f"face {row} refers to a vertex that does not exist ({faces[row].tolist()})"
        )
    return vertices, faces.astype(np.int32)


def repair_surface(
    region: str, vertices: np.ndarray, faces: np.ndarray, max_hole_edges: int
) -> tuple[Surface, dict[str, int]]:
    """The surface closed, manifold and outward-oriented, and a count of each repair made.

    Repairs, in order: duplicate vertices merged, duplicate and zero-area faces removed,
    non-manifold edges and vertices split or removed, holes of at most max_hole_edges boundary
    edges closed, orientation made coherent and outward. Raises BuildError when the result is
    still open, non-manifold or encloses no volume.
    """
    vertices, faces = check_arrays(region, vertices, faces)
    pymeshlab = _meshlab()
    repairs: dict[str, int] = {}
    scale = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    if scale == 0:
        raise BuildError(region, "all vertices are at one point (the mesh has no extent)")
    edge = np.linalg.norm(vertices[faces[:, 1]] - vertices[faces[:, 0]], axis=1).mean()
    areas = triangle_areas(vertices, faces)
    degenerate = areas <= DEGENERATE_AREA_RATIO * max(edge, scale * 1e-6) ** 2
    if degenerate.all():
        raise BuildError(region, f"all {len(faces)} faces have zero area (nothing to mesh)")

    # A face that repeats a vertex has zero area; pymeshlab would drop it without a word.
    repeated = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    )
    if repeated.any():
        repairs["removed_zero_area_faces"] = int(repeated.sum())
        faces, degenerate = faces[~repeated], degenerate[~repeated]
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))

    def count(name: str, filter_name: str, **kwargs) -> None:
        mesh = meshes.current_mesh()
        before = (mesh.vertex_number(), mesh.face_number())
        getattr(meshes, filter_name)(**kwargs)
        mesh = meshes.current_mesh()
        changed = (
            abs(before[0] - mesh.vertex_number())
            if name.endswith("vertices")
            else abs(before[1] - mesh.face_number())
        )
        if changed:
            repairs[name] = repairs.get(name, 0) + changed

    count("merged_duplicate_vertices", "meshing_remove_duplicate_vertices")
    count("removed_duplicate_faces", "meshing_remove_duplicate_faces")
    count("removed_zero_area_faces", "meshing_remove_null_faces")
    if degenerate.any():
        # pymeshlab removes exactly-zero faces; ours catch near-zero ones too.
        mesh = meshes.current_mesh()
        v, f = mesh.vertex_matrix(), mesh.face_matrix()
        keep = triangle_areas(v, f) > DEGENERATE_AREA_RATIO * max(edge, scale * 1e-6) ** 2
        if not keep.all():
            repairs["removed_zero_area_faces"] = repairs.get("removed_zero_area_faces", 0) + int(
                (~keep).sum()
            )
            meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=v, face_matrix=f[keep]))
    if _most_edge_uses(meshes.current_mesh().face_matrix()) > 2:  # Else it has none to do.
        count("removed_faces_at_non_manifold_edges", "meshing_repair_non_manifold_edges")
    count("split_non_manifold_vertices", "meshing_repair_non_manifold_vertices")
    count("removed_unreferenced_vertices", "meshing_remove_unreferenced_vertices")
    topology = meshes.get_topological_measures()
    if topology["boundary_edges"] > 0 and max_hole_edges > 0:
        try:
            result = meshes.meshing_close_holes(
                maxholesize=int(max_hole_edges), newfaceselected=False
            )
        except pymeshlab.PyMeshLabException as error:  # e.g. non-manifold leftovers
            raise BuildError(region, f"cannot close its holes: {error}") from None
        closed = int((result or {}).get("closed_holes", 0))
        if closed:
            repairs["closed_holes"] = closed
            repairs["faces_added_in_holes"] = int((result or {}).get("new_faces", 0))
            repairs["boundary_edges_before"] = int(topology["boundary_edges"])
        count("removed_zero_area_faces", "meshing_remove_null_faces")
        topology = meshes.get_topological_measures()
    if topology["non_two_manifold_edges"] > 0 or topology["non_two_manifold_vertices"] > 0:
        raise BuildError(
            region,
            f"not manifold after repair: {topology['non_two_manifold_edges']} non-manifold "
            f"edges, {topology['non_two_manifold_vertices']} non-manifold vertices",
        )
    if topology["boundary_edges"] > 0:
        raise BuildError(
            region,
            f"open mesh: {topology['boundary_edges']} boundary edges in "
            f"{max(topology['number_holes'], 1)} holes remain after closing holes of up to "
            f"{max_hole_edges} edges (close them in the modeller, or allow larger holes)",
        )
    before_orientation = meshes.current_mesh().face_matrix().copy()
    if _most_edge_uses(before_orientation, directed=True) > 1:  # Else coherent already.
        meshes.meshing_re_orient_faces_coherently()
    mesh = meshes.current_mesh()
    out_vertices = np.asarray(mesh.vertex_matrix(), dtype=np.float64)
    out_faces = np.asarray(mesh.face_matrix(), dtype=np.int32)
    if out_faces.shape == before_orientation.shape:
        flipped = int((~np.all(out_faces == before_orientation, axis=1)).sum())
        if flipped:
            repairs["reoriented_faces"] = flipped
    volume = signed_volume(out_vertices, out_faces)
    extent = out_vertices.max(axis=0) - out_vertices.min(axis=0)
    if abs(volume) <= MIN_VOLUME_RATIO * float(np.prod(np.maximum(extent, scale * 1e-6))):
        raise BuildError(region, "encloses no volume (a flat or inside-out-and-back surface)")
    if volume < 0:
        out_faces = out_faces[:, ::-1].copy()
        repairs["inverted_inside_out"] = 1
    return Surface(out_vertices, out_faces), repairs


def _most_edge_uses(faces: np.ndarray, directed: bool = False) -> int:
    """How many faces use the edge most used (directed: run in the same direction, which
    two faces of a coherently oriented manifold never do). Cheaper than pymeshlab's filters
    on a scan, which then need not run: a mesh with none above 2 has no non-manifold edge."""
    if len(faces) == 0:
        return 0
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).astype(np.int64)
    if not directed:
        edges = np.sort(edges, axis=1)
    keys = np.sort(edges[:, 0] * (int(faces.max()) + 1) + edges[:, 1])
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1], True])
    return int(np.diff(starts).max())


def hausdorff(
    meshes,
    first: int,
    second: int,
    samples: int | None = None,
    between=None,
    first_vertices_only: bool = False,
    stop_above: float | None = None,
    back_from: float | None = None,
) -> float:
    """Symmetric Hausdorff distance between two meshes of a MeshSet (vertex + face samples);
    between() is called after the first of its two ways (each way costs seconds on a scan).
    first_vertices_only: the first way samples the first mesh's vertices alone (a screen on
    a scan, whose vertices lie closer together than face samples would). stop_above: when
    the first way finds more than this, that is returned without measuring the other (the
    distance is more than it either way). back_from: the other way is measured only when the
    first found more than this (math.inf: the first way alone, a one-sided distance).

    A measure of both ways of at least AT_ONCE_SAMPLES samples each, where this process can
    fork (forked.py), measures most of the other way in a forked child while it measures the
    first way and the rest of the other (at_once): the same samples, spread alike."""
    pymeshlab = _meshlab()
    largest = max(meshes.mesh(first).face_number(), meshes.mesh(second).face_number())
    samples = samples or max(20_000, 4 * largest)
    far = pymeshlab.PercentageValue(50)

    def way(sampled: int, target: int, count: int, faces: bool = True) -> float:
        return float(
            meshes.get_hausdorff_distance(
                sampledmesh=sampled, targetmesh=target, samplevert=True, sampleface=faces,
                samplenum=count, maxdist=far,
            )["max"]
        )  # fmt: skip

    full = back_from is None and not first_vertices_only
    if full and samples >= AT_ONCE_SAMPLES and forked.can_fork():
        found = _at_once(meshes, first, second, samples, way, between, stop_above)
        if found is not None:
            return found
    there = way(first, second, samples, faces=not first_vertices_only)
    if stop_above is not None and there > stop_above:
        return there
    if back_from is not None and there <= back_from:
        return there
    if between is not None:
        between()
    return max(there, way(second, first, samples))


# A measure of a scan's surface (4 samples per face of the larger mesh each way) measures
# its two ways at once: below this, a way costs little more than starting the child.
AT_ONCE_SAMPLES = 100_000
# The share of the way back (from the second mesh's samples to the first) that the child
# measures: the parent measures the way there and the rest. On a scan the way back, to the
# scan's many faces, costs about twice the way there, to the candidate's few, so that each
# then measures about as long.
BACK_IN_CHILD = 0.75


def _at_once(
    meshes, first: int, second: int, samples: int, way, between, stop_above
) -> float | None:
    """hausdorff's two ways at once: the second mesh cut in two parts (its faces in order,
    BACK_IN_CHILD of its area in the first), each sampled with its share of the samples (the
    face samples are spread by area, the vertices all sampled) and measured against the
    first mesh, the first part in a forked child. None, measuring nothing, when a part would
    be empty (a face of over BACK_IN_CHILD of the area)."""
    current = meshes.current_mesh_id()
    mesh = meshes.mesh(second)
    vertices, faces = mesh.vertex_matrix(), mesh.face_matrix()
    areas = triangle_areas(vertices, faces)
    in_child = np.cumsum(areas) <= BACK_IN_CHILD * areas.sum()
    if in_child.all() or not in_child.any():
        return None
    parts = []
    for chosen in (in_child, ~in_child):
        used, index = np.unique(faces[chosen], return_inverse=True)
        meshes.add_mesh(
            _meshlab().Mesh(vertex_matrix=vertices[used], face_matrix=index.reshape(-1, 3))
        )
        parts.append(meshes.current_mesh_id())
    child_samples = round(samples * areas[in_child].sum() / max(areas.sum(), 1e-300))
    try:
        with Beside(lambda: way(parts[0], first, max(child_samples, 1))) as other:
            there = way(first, second, samples)
            if stop_above is not None and there > stop_above:
                return there
            if between is not None:
                between()
            mine = way(parts[1], first, max(samples - child_samples, 1))
            return max(there, mine, other.result())
    finally:
        for part in parts:
            meshes.set_current_mesh(part)
            meshes.delete_current_mesh()
        meshes.set_current_mesh(current)


def one_sided_deviation(sampled: Surface, target: Surface) -> float:
    """How far points of ``sampled`` lie from ``target`` at most, in mm (pymeshlab's
    Hausdorff distance one way, vertex and face samples as in hausdorff)."""
    pymeshlab = _meshlab()
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=sampled.vertices, face_matrix=sampled.faces))
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=target.vertices, face_matrix=target.faces))
    samples = max(20_000, 4 * max(len(sampled.faces), len(target.faces)))
    result = meshes.get_hausdorff_distance(
        sampledmesh=0, targetmesh=1, samplevert=True, sampleface=True, samplenum=samples,
        maxdist=pymeshlab.PercentageValue(50),
    )  # fmt: skip
    return float(result["max"])


def surface_deviation(a: Surface, b: Surface) -> float:
    """Symmetric Hausdorff distance in mm between two surfaces (pymeshlab, sampled)."""
    pymeshlab = _meshlab()
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=a.vertices, face_matrix=a.faces))
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=b.vertices, face_matrix=b.faces))
    return hausdorff(meshes, 0, 1)


def _merged_meshset(surfaces: list[Surface]):
    """A pymeshlab MeshSet holding all the surfaces as one mesh (faces in input order)."""
    pymeshlab = _meshlab()
    vertices = np.concatenate([s.vertices for s in surfaces])
    offsets = np.cumsum([0] + [len(s.vertices) for s in surfaces[:-1]])
    faces = np.concatenate([s.faces + o for s, o in zip(surfaces, offsets, strict=True)])
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    return meshes


def distance_to_surfaces(points: np.ndarray, surfaces: list[Surface], max_mm: float) -> np.ndarray:
    """(n,) unsigned distance from each point to the nearest surface, capped at max_mm.

    pymeshlab's point-to-mesh distance with a spatial grid; points farther than max_mm get
    max_mm (a small cap keeps it fast).
    """
    pymeshlab = _meshlab()
    meshes = _merged_meshset(surfaces)
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(points, dtype=np.float64)))
    meshes.compute_scalar_by_distance_from_another_mesh_per_vertex(
        measuremesh=1, refmesh=0, signeddist=False, maxdist=pymeshlab.PureValue(float(max_mm))
    )
    return np.minimum(np.abs(meshes.mesh(1).vertex_scalar_array()), max_mm)


def self_intersecting_faces(surfaces: list[Surface]) -> np.ndarray:
    """(f,) bool over the surfaces' faces, concatenated: faces that cross another face."""
    return crossing_faces(_merged_meshset(surfaces))


def crossing_faces(meshes) -> np.ndarray:
    """(f,) bool over the faces of a MeshSet's current mesh: faces that cross another face
    (the mesh's selection cleared again)."""
    meshes.compute_selection_by_self_intersections_per_face()
    crossing = np.asarray(meshes.current_mesh().face_selection_array(), dtype=bool)
    meshes.set_selection_none()
    return crossing
