"""Lighter visual meshes: error-bounded simplification of a model's render-only meshes.

Software rendering (llvmpipe/OSMesa) spends most of a frame on vertices, and the Menagerie UR5e
and Robotiq 2F-85 visual meshes have 185k triangles (390k vertices): CAD tessellations, dense
where they need not be. :func:`simplify_visual_meshes` replaces them, in an
:class:`mujoco.MjSpec` straight from its MJCF file, with simplified copies whose surface stays
within about ``visual_mesh_error`` metres of the original (0.5 mm by default: ~17k triangles
for the UR5e + 2F-85, sub-pixel for the scene cameras). ``visual_mesh_error=0`` keeps the
original meshes. Only *visual* geoms change (mesh geoms with ``contype = conaffinity = 0`` named
in no contact pair), and physics stays bit-identical:

- a mesh that a colliding geom also uses keeps its full data for that geom; its visual geoms get
  a simplified copy named ``<mesh>_visual``;
- a body whose mass and inertia the compiler infers from its geoms (no ``<inertial>``) gets the
  inertial the full-detail model computes, so lighter visual meshes cannot change it.

Ray casts (``mj_ray``, rangefinders) see the simplified meshes, as cameras do.

The simplifier is meshoptimizer's edge collapse (``meshopt_simplify`` with an absolute error
bound): it keeps a subset of the original vertices, so nothing moves off the surface, and it
spends triangles where the shape needs them. Vertices are welded first (OBJ files repeat a
vertex per face corner, which would block every collapse). The simplified meshes carry no
normals: MuJoCo computes them (the Menagerie OBJ files store flat per-triangle normals, which
only look smooth because their triangles are tiny).

Results are cached as ``.npz`` in :func:`cache_dir` (``$RMB_LEROBOT_CACHE/visual_meshes``, else
``$XDG_CACHE_HOME/rmb_lerobot/visual_meshes``, else ``~/.cache/rmb_lerobot/visual_meshes``),
keyed by the MJCF text, the mesh files' paths, sizes and modification times, the error bound
and the versions of MuJoCo, meshoptimizer and this algorithm. A miss compiles the full-detail
model once and simplifies (2-3 s for the UR5e + 2F-85 on 2 cores); a hit reads ~0.2 MB.
Without a writable cache directory the work is redone once per process.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import tempfile
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.options import DEFAULT_VISUAL_MESH_ERROR

logger = logging.getLogger(__name__)

WELD_TOLERANCE = 1e-6
"""Vertices in the same grid cell of this size (metres) are merged before simplifying."""
VISUAL_SUFFIX = "_visual"
_ALGORITHM_VERSION = 1
_memory_cache: dict[str, SimplifiedMeshes] = {}

Mesh = tuple[np.ndarray, np.ndarray]
Inertial = tuple[float, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class SimplifiedMeshes:
    """What :func:`simplify_visual_meshes` writes into a spec (the cached payload).

    ``meshes`` maps a mesh name to ``(vertices (n, 3) float32, faces (m, 3) int32)`` in the
    mesh file's frame, already scaled. ``inertials`` maps a body name to the full-detail
    ``(mass, ipos (3), iquat (4), inertia (3))`` of bodies whose inertia is inferred from geoms.
    """

    meshes: dict[str, Mesh]
    inertials: dict[str, Inertial]

    @property
    def num_faces(self) -> int:
        return sum(len(faces) for _, faces in self.meshes.values())


def check_visual_mesh_error(visual_mesh_error: float) -> float:
    """``visual_mesh_error`` as a finite float >= 0, or ``ValueError``."""
    error = float(visual_mesh_error)
    if not (np.isfinite(error) and error >= 0.0):
        raise ValueError(f"visual_mesh_error must be >= 0 metres, got {visual_mesh_error!r}")
    return error


def cache_dir() -> Path:
    """Where simplified meshes are cached (see the module docstring)."""
    root = os.environ.get("RMB_LEROBOT_CACHE")
    if root:
        return Path(root) / "visual_meshes"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "rmb_lerobot" / "visual_meshes"


# ---------------------------------------------------------------------------------- geometry
def weld(
    vertices: np.ndarray, faces: np.ndarray, tolerance: float = WELD_TOLERANCE
) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices sharing a ``tolerance``-sized grid cell (at their mean); drop the faces
    that become degenerate or duplicated, and unused vertices."""
    cells = np.floor(vertices / tolerance).astype(np.int64)
    cells -= cells.min(axis=0)
    span = cells.max(axis=0) + 1
    keys = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]
    _, label, count = np.unique(keys, return_inverse=True, return_counts=True)
    merged = np.zeros((len(count), 3))
    np.add.at(merged, label.ravel(), vertices)
    merged /= count[:, None]
    tri = label.ravel()[faces]
    tri = tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])]
    _, first = np.unique(np.sort(tri, axis=1), axis=0, return_index=True)
    return _compact(merged, tri[np.sort(first)])


def _compact(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used, index = np.unique(faces, return_inverse=True)
    return vertices[used], index.reshape(-1, 3).astype(np.int32)


def simplify_mesh(
    vertices: np.ndarray, faces: np.ndarray, max_error: float
) -> tuple[np.ndarray, np.ndarray]:
    """Welded, then edge-collapsed until the next collapse would move the surface by more than
    about ``max_error`` (same units as ``vertices``). Returns ``(vertices, faces)``."""
    import meshoptimizer

    vertices, faces = weld(np.asarray(vertices, dtype=np.float64), np.asarray(faces))
    indices = faces.astype(np.uint32).ravel()
    out = np.zeros_like(indices)
    count = meshoptimizer.simplify(
        out,
        indices,
        vertices.astype(np.float32),
        target_index_count=0,
        target_error=float(max_error),
        options=meshoptimizer.SIMPLIFY_ERROR_ABSOLUTE,
    )
    return _compact(vertices, out[:count].reshape(-1, 3))


# ---------------------------------------------------------------------------------- spec edits
def _visual_geoms(spec: mujoco.MjSpec) -> dict[str, list[tuple[mujoco.MjsGeom, str] | None]]:
    """Mesh name -> ``(geom, body name)`` of each visual geom using it, ``None`` for each other
    geom using it (one that collides, or is named in a contact pair)."""
    in_pairs = {name for pair in spec.pairs for name in (pair.geomname1, pair.geomname2)}
    users: dict[str, list[tuple[mujoco.MjsGeom, str] | None]] = {}
    for body in spec.bodies:
        for geom in body.geoms:
            if geom.type != mujoco.mjtGeom.mjGEOM_MESH or not geom.meshname:
                continue
            visual = geom.contype == 0 and geom.conaffinity == 0 and geom.name not in in_pairs
            users.setdefault(geom.meshname, []).append((geom, body.name) if visual else None)
    return users


def _source_key(spec: mujoco.MjSpec, source: Path, max_error: float) -> str:
    """Cache key: MJCF text, mesh files (path, size, mtime), error bound, library versions."""
    digest = hashlib.blake2b(Path(source).read_bytes(), digest_size=16)
    mesh_dir = Path(spec.modelfiledir or Path(source).parent) / (spec.meshdir or "")
    files = []
    for mesh in spec.meshes:
        if mesh.file:
            path = (mesh_dir / mesh.file).resolve()
            stat = path.stat()
            files.append([mesh.name, str(path), stat.st_size, stat.st_mtime_ns])
    meta = {
        "files": files,
        "max_error": repr(max_error),
        "weld": repr(WELD_TOLERANCE),
        "algorithm": _ALGORITHM_VERSION,
        "mujoco": mujoco.__version__,
        "meshoptimizer": version("meshoptimizer"),
    }
    digest.update(json.dumps(meta, sort_keys=True).encode())
    return digest.hexdigest()


def compute_simplified_meshes(spec: mujoco.MjSpec, max_error: float) -> SimplifiedMeshes:
    """Compile a copy of ``spec`` in full detail and simplify its visual meshes (no cache)."""
    users = _visual_geoms(spec)
    model = spec.copy().compile()  # a copy: compiling fills the spec's meshes with file data
    meshes: dict[str, Mesh] = {}
    pinned: set[str] = set()
    for name, geoms in users.items():
        visual = [user for user in geoms if user is not None]
        mesh_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MESH, name)
        if not visual or model.mesh_texcoordnum[mesh_id] > 0:
            continue
        num_faces = int(model.mesh_facenum[mesh_id])
        vert_adr, face_adr = model.mesh_vertadr[mesh_id], model.mesh_faceadr[mesh_id]
        vertices = model.mesh_vert[vert_adr : vert_adr + model.mesh_vertnum[mesh_id]]
        faces = model.mesh_face[face_adr : face_adr + num_faces]
        # Compiled vertices sit in the mesh's inertial frame; go back to the file's frame so the
        # geoms keep their poses (the compiler re-centres the new mesh the same way).
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, model.mesh_quat[mesh_id])
        vertices = vertices.astype(np.float64) @ rot.reshape(3, 3).T + model.mesh_pos[mesh_id]
        new_vertices, new_faces = simplify_mesh(vertices, faces, max_error)
        if not 4 <= len(new_faces) < num_faces:
            continue
        meshes[name] = (new_vertices.astype(np.float32), new_faces)  # float32, as MuJoCo's
        # Bodies without <inertial> sum their geoms' inertias: pin the full-detail result.
        pinned.update(body for _, body in visual if not spec.body(body).explicitinertial)
    inertials = {}
    for body_name in sorted(pinned):
        body = model.body(body_name)
        inertials[body_name] = (
            float(body.mass[0]),
            body.ipos.copy(),
            body.iquat.copy(),
            body.inertia.copy(),
        )
    return SimplifiedMeshes(meshes, inertials)


def _save(path: Path, result: SimplifiedMeshes) -> None:
    arrays: dict[str, np.ndarray] = {
        "mesh_names": np.array(list(result.meshes), dtype=str),
        "body_names": np.array(list(result.inertials), dtype=str),
    }
    for i, (vertices, faces) in enumerate(result.meshes.values()):
        arrays[f"v{i}"], arrays[f"f{i}"] = vertices, faces
    for i, (mass, ipos, iquat, inertia) in enumerate(result.inertials.values()):
        arrays[f"b{i}"] = np.concatenate([[mass], ipos, iquat, inertia])
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def _load(path: Path) -> SimplifiedMeshes:
    with np.load(path, allow_pickle=False) as data:
        meshes = {
            str(name): (data[f"v{i}"], data[f"f{i}"]) for i, name in enumerate(data["mesh_names"])
        }
        inertials = {}
        for i, name in enumerate(data["body_names"]):
            b = data[f"b{i}"]
            inertials[str(name)] = (float(b[0]), b[1:4], b[4:8], b[8:11])
    return SimplifiedMeshes(meshes, inertials)


def simplified_meshes(
    spec: mujoco.MjSpec, source: Path, max_error: float, *, cache: Path | bool | None = True
) -> SimplifiedMeshes:
    """The simplified visual meshes of ``spec`` (as loaded from ``source``), from the cache
    when it has them. ``cache``: ``True`` for :func:`cache_dir`, a directory, or ``False``."""
    key = _source_key(spec, source, max_error)
    if key in _memory_cache:
        return _memory_cache[key]
    directory = cache_dir() if cache is True else (Path(cache) if cache else None)
    path = directory / f"{Path(source).stem}-{key}.npz" if directory else None
    result = None
    if path is not None and path.is_file():
        try:
            result = _load(path)
        except (OSError, ValueError, KeyError) as err:
            logger.warning("ignoring unreadable visual mesh cache %s: %s", path, err)
    if result is None:
        result = compute_simplified_meshes(spec, max_error)
        if path is not None:
            try:
                _save(path, result)
            except OSError as err:
                logger.warning("cannot cache simplified meshes in %s: %s", path.parent, err)
    _memory_cache[key] = result
    return result


def apply_simplified_meshes(spec: mujoco.MjSpec, result: SimplifiedMeshes) -> None:
    """Point ``spec``'s visual geoms at the simplified meshes and pin inferred inertials."""
    users = _visual_geoms(spec)
    for name, (vertices, faces) in result.meshes.items():
        geoms = users.get(name, [])
        if all(user is not None for user in geoms):
            target = spec.mesh(name)  # render-only: replace its data in place (same ids)
        else:
            target = spec.add_mesh(name=name + VISUAL_SUFFIX)
            for user in geoms:
                if user is not None:
                    user[0].meshname = target.name
        target.file = ""
        target.scale = [1.0, 1.0, 1.0]
        target.refpos = [0.0, 0.0, 0.0]
        target.refquat = [1.0, 0.0, 0.0, 0.0]
        # Shell inertia needs no closed volume. It only places the mesh frame here: the geom's
        # own mass never counts, its body has an explicit or a pinned inertial.
        target.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        target.uservert = np.asarray(vertices, dtype=np.float32).ravel()
        target.userface = np.asarray(faces, dtype=np.int32).ravel()
        for field in ("usernormal", "userfacenormal", "usertexcoord", "userfacetexcoord"):
            setattr(target, field, [])
    for body_name, (mass, ipos, iquat, inertia) in result.inertials.items():
        body = spec.body(body_name)
        body.explicitinertial = True
        body.mass, body.ipos, body.iquat, body.inertia = mass, ipos, iquat, inertia
        body.fullinertia = [np.nan] * 6


def simplify_visual_meshes(
    spec: mujoco.MjSpec,
    source: Path,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    *,
    cache: Path | bool | None = True,
) -> SimplifiedMeshes | None:
    """Simplify the visual meshes of ``spec``, freshly loaded from the MJCF file ``source``.

    Returns what was applied; ``None`` when ``visual_mesh_error`` is 0 (``spec`` unchanged).
    """
    max_error = check_visual_mesh_error(visual_mesh_error)
    if max_error == 0.0:
        return None
    if spec.compiler.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE:
        # Every explicit inertial would be recomputed from the (simplified) geoms.
        logger.warning("%s infers all inertials from geoms; its visual meshes are kept", source)
        return None
    result = simplified_meshes(spec, source, max_error, cache=cache)
    apply_simplified_meshes(spec, result)
    return result
