"""Triangle meshes read from files (OBJ, STL, PLY, OFF, glTF): a cloth of any mesh, a rigid
body's shape.

:func:`read_triangle_mesh` reads one triangle mesh with trimesh and returns the arrays a cloth
or a body is built from: the distinct vertex positions and the triangles over them. A file is
refused, with its path in the message, when it is not a regular file (a directory, a device such
as ``/dev/zero``, a FIFO: checked on the open descriptor, before anything is read, so nothing
blocks), larger than :data:`MAX_MESH_BYTES` (from its size, before reading: a 2 GB sparse file
costs nothing), empty, not in a format named by its suffix (:data:`MESH_FORMATS`), unreadable in
that format, or not one triangle mesh — a scene of several meshes, a point cloud, lines, a mesh
without triangles or with a vertex that is not finite. Nothing is fetched: a glTF file must hold
its buffers (or be a ``.glb``).

Vertices at the same position are merged — an STL file repeats each vertex in every triangle
around it, an OBJ file splits one where its texture coordinates change — so that the cloth's
triangles share edges (and springs). The vertices keep the order in which trimesh gives them
(for OBJ and PLY, the file's order, less the vertices no triangle uses), each where it first
appears: the indices a scene's ``pinned`` names are those of :func:`read_triangle_mesh`'s
``vertices``.

This module imports nothing of visviva but its errors: the entity kinds that take a ``path``
(``cloth_mesh``, ``body``) read their file with it when they are added to a builder (see
:mod:`visviva.entities.mesh_files` and the layer table in docs/architecture.md); the physics
packages take vertices and triangles, never a path.
"""

from __future__ import annotations

import io
import os
import stat
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError

__all__ = ["MAX_MESH_BYTES", "MESH_FORMATS", "MeshFileError", "read_triangle_mesh"]

#: Largest mesh file read [bytes]: about 2.5 million triangles as binary STL, more than a cloth
#: stepped on a laptop holds.
MAX_MESH_BYTES = 128 * 2**20
#: File suffixes read, and trimesh's name for each format.
MESH_FORMATS = {
    ".obj": "obj",
    ".stl": "stl",
    ".ply": "ply",
    ".off": "off",
    ".glb": "glb",
    ".gltf": "gltf",
}
#: Formats that are text (refused, if not UTF-8, before trimesh guesses another encoding).
_TEXT = ("obj", "off", "gltf")


class MeshFileError(ModelError):
    """A mesh file refused, naming the file.

    Attributes:
        path: The file, as given.
    """

    def __init__(self, path: str, problem: str) -> None:
        super().__init__(f"the mesh file {path!r} {problem}")
        self.path = path


def read_triangle_mesh(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """The triangle mesh in the file at ``path`` (see the module docstring).

    Returns:
        ``vertices`` ``(n, 3)`` float64 [the file's units, metres for a scene] and
        ``triangles`` ``(t, 3)`` int64 (indices into ``vertices``).

    Raises:
        MeshFileError: For a file that is not one readable triangle mesh, saying why.
    """
    name = os.fspath(path)
    kind = MESH_FORMATS.get(Path(name).suffix.lower())
    if kind is None:
        raise MeshFileError(
            name,
            "is not in a mesh format read here: its name must end in " + ", ".join(MESH_FORMATS),
        )
    data = _read_limited(name)
    if kind in _TEXT or (kind == "stl" and not _binary_stl(data)):
        try:
            data.decode("utf-8")
        except UnicodeDecodeError as exc:
            where = f"byte 0x{data[exc.start]:02x} at offset {exc.start}"
            if kind == "stl":
                raise MeshFileError(
                    name,
                    "is neither a binary STL file (its size does not match the triangle count "
                    f"in its header) nor UTF-8 text ({where}), as an ASCII STL file must be",
                ) from None
            raise MeshFileError(
                name, f"is not UTF-8 text ({where}), as a {kind.upper()} file must be"
            ) from None
    mesh = _load(name, data, kind)
    return _merged(name, mesh)


def _read_limited(name: str) -> bytes:
    """The bytes of a regular, non-empty file of at most :data:`MAX_MESH_BYTES`, opened
    without blocking (a FIFO) and judged by its descriptor, not its name."""
    try:
        descriptor = os.open(name, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise MeshFileError(name, f"cannot be opened: {exc.strerror}") from None
    status = os.fstat(descriptor)
    if not stat.S_ISREG(status.st_mode) or status.st_size > MAX_MESH_BYTES:
        os.close(descriptor)
        if stat.S_ISDIR(status.st_mode):
            raise MeshFileError(name, "is a directory; give the path of a mesh file")
        if not stat.S_ISREG(status.st_mode):
            raise MeshFileError(name, "is not a regular file (a device, a pipe, a socket)")
        raise MeshFileError(
            name,
            f"holds {status.st_size} bytes, more than the {MAX_MESH_BYTES} a mesh file may have: "
            "simplify the mesh",
        )
    with os.fdopen(descriptor, "rb") as handle:
        try:
            data = handle.read(MAX_MESH_BYTES + 1)
        except OSError as exc:
            raise MeshFileError(name, f"cannot be read: {exc.strerror}") from None
    if len(data) > MAX_MESH_BYTES:  # it grew while being read
        raise MeshFileError(name, f"holds more than {MAX_MESH_BYTES} bytes")
    if not data:
        raise MeshFileError(name, "is empty")
    return data


def _binary_stl(data: bytes) -> bool:
    """True if ``data`` is laid out as a binary STL: an 80-byte header, the triangle count,
    then 50 bytes per triangle."""
    if len(data) < 84:
        return False
    count = int.from_bytes(data[80:84], "little")
    return len(data) == 84 + 50 * count


def _load(name: str, data: bytes, kind: str) -> object:
    """trimesh's reading of ``data`` as ``kind`` (a mesh, a scene, points ...)."""
    import trimesh

    options: dict[str, Any] = (
        {"maintain_order": True, "skip_materials": True} if kind == "obj" else {}
    )
    try:
        return trimesh.load(io.BytesIO(data), file_type=kind, process=False, **options)
    except Exception as exc:  # a parser of untrusted bytes fails in many ways (and kinds)
        text = str(exc).strip()
        detail = text.splitlines()[0][:200] if text else type(exc).__name__
        raise MeshFileError(name, f"cannot be read as {kind.upper()}: {detail}") from None


def _merged(name: str, loaded: object) -> tuple[np.ndarray, np.ndarray]:
    """The one triangle mesh of ``loaded``, its vertices at the same position merged."""
    import trimesh

    mesh = loaded
    if isinstance(loaded, trimesh.Scene):
        placed = loaded.graph.nodes_geometry
        if not placed:
            raise MeshFileError(name, "holds no mesh")
        if len(placed) > 1:
            raise MeshFileError(
                name,
                f"is a scene of {len(placed)} meshes; a body is one triangle mesh: export the "
                "one you want on its own",
            )
        mesh = loaded.dump()[0]  # the one mesh, placed by its node's transform
    if isinstance(mesh, trimesh.PointCloud):
        raise MeshFileError(name, "holds points without triangles (a point cloud)")
    if not isinstance(mesh, trimesh.Trimesh):
        raise MeshFileError(name, f"holds {type(mesh).__name__}, not a triangle mesh")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    triangles = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    if not triangles.shape[0]:
        raise MeshFileError(name, "holds no triangles")
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        index = int(np.flatnonzero(bad)[0])
        raise MeshFileError(
            name, f"has a vertex that is not finite: vertex {index} is at {vertices[index]}"
        )
    # Merge equal positions (+ 0.0 makes −0.0 equal to 0.0), keeping first appearances in order.
    _, first, inverse = np.unique(vertices + 0.0, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.shape[0])
    return vertices[first[order]], rank[inverse.reshape(-1)][triangles]
