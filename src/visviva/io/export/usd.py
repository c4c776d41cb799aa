"""Universal Scene Description (USD) export: time-sampled geometry under one ``/World`` prim.

Written with Pixar's ``usd-core`` (``pxr``), following the UsdGeom schemas (openusd.org,
"UsdGeom" API documentation and the Universal Scene Description glossary):

* stage metadata ``upAxis = "Y"``, ``metersPerUnit = 1``, ``timeCodesPerSecond`` and
  ``framesPerSecond`` equal to the export's ``fps``, ``startTimeCode = 0`` and
  ``endTimeCode = N − 1``: time code ``k`` is output frame ``k``, ``k/fps`` seconds after the
  first recorded frame;
* ``/World`` (an ``Xform``) is the default prim, so importers that load only the default prim
  (Blender, references without a prim path) get everything;
* ``/World/points`` (``UsdGeom.Points``): the points not used by any face, with time-sampled
  ``points`` and ``extent``, per-point ``widths`` (2 × radius) and, for a recording with
  colours, ``primvars:displayColor`` (``vertex`` interpolation, sRGB as recorded); widths and
  colours are time-sampled when they change;
* points that are born and die (particles of emitters): each time sample of ``points``,
  ``widths``, ``primvars:displayColor`` and ``ids`` holds only the points alive at that frame,
  ``ids`` being each one's slot in the recording (int64), so a particle keeps its id while it
  lives. UsdGeomPoints has no ``invisibleIds`` (that is UsdGeomPointInstancer's), and arrays
  whose length changes from sample to sample are what Blender's point-cloud reader (it
  reallocates the cloud when the count changes, and reads widths and primvars per frame) and
  Houdini (``ids`` becomes its ``id`` attribute) import; a frame with no live point has empty
  arrays and the empty extent usd-core itself computes for no points;
* ``/World/edges`` (``UsdGeom.BasisCurves``, ``type = linear``, ``wrap = nonperiodic``): one
  two-vertex curve per edge, time-sampled ``points`` (the two ends of every edge, in edge
  order) and ``extent``, and a constant width of half the thinnest diameter among points
  with a radius;
* ``/World/mesh`` (``UsdGeom.Mesh``): the points the triangles use (in the recording's order)
  and the triangles as ``faceVertexCounts`` (all 3) and ``faceVertexIndices`` into them,
  ``orientation = rightHanded`` (counter-clockwise seen from outside,
  the recording's convention), ``subdivisionScheme = none`` (a simulation mesh is the surface
  itself, not a cage to be smoothed), ``doubleSided`` (cloth has no inside), time-sampled
  ``points`` and ``extent``.

* ``/World/bodies/NAME`` (``UsdGeom.Xform``), one per rigid body (its name made a valid,
  unique prim name): the ops ``xformOp:translate`` (``double3``, the body's own origin [m])
  and ``xformOp:orient`` (``quatd``, (w, x, y, z), body to world), time-sampled, in that
  order, so a point ``v`` of the body is at ``translate + R(orient) v``; the quaternions' signs
  keep each sample in the hemisphere of the one before, so interpolation turns the short way.
  Its child ``NAME`` (``UsdGeom.Mesh``) is static: the surface in the body's own axes, with
  vertex ``normals``, ``extent``, ``orientation = rightHanded``, ``subdivisionScheme = none``
  and a constant ``primvars:displayColor``. No vertex moves per frame: the animation is the
  transform alone: Blender imports each body as one object named ``NAME`` whose Transform
  Cache constraint reads the ops from the file.

* ``/World/scenery/NAME`` (``UsdGeom.Mesh`` under a ``Scope``), one per drawn static collider
  (sphere, box, mesh; planes have no finite surface and are left out): the surface in the
  world frame with vertex ``normals``, ``extent``, ``orientation = rightHanded``,
  ``subdivisionScheme = none`` and a constant ``primvars:displayColor``, without time samples.

Point-based ``points`` are float32 (``point3f[]``), so positions keep float32 precision; the
bodies' transforms are float64 (double and ``quatd``), exactly as recorded.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..._version import __version__
from ...simulation.body_geometry import BodyGeometry
from ...simulation.scenery import Scenery
from ._files import all_or_nothing
from ._frames import ExportFrames

__all__ = ["USD_ENCODINGS", "write_usd"]

#: File encodings usd-core writes: text and binary ("crate").
USD_ENCODINGS = ("usda", "usdc")
#: Width of edge curves, as a fraction of the thinnest point diameter.
_EDGE_WIDTH_FRACTION = 0.5


#: The extent of no points, as usd-core computes it: an empty (inverted) box.
_EMPTY_EXTENT = np.array([[np.finfo(np.float32).max] * 3, [-np.finfo(np.float32).max] * 3])


def _extent(positions: np.ndarray, half_width: np.ndarray | float) -> np.ndarray:
    """Bounding box [m] of one frame, float32 ``(2, 3)``: lower and upper corner, widths in."""
    if positions.shape[0] == 0:
        return _EMPTY_EXTENT.astype(np.float32)
    pad = np.asarray(half_width, dtype=np.float64).reshape(-1, 1)
    return np.stack([(positions - pad).min(axis=0), (positions + pad).max(axis=0)]).astype(
        np.float32
    )


def _animate(
    prim: Any, frames: ExportFrames, chosen: np.ndarray | None, half_width: np.ndarray | float
) -> Callable[[int], None]:
    """A writer of the time samples of ``points`` and ``extent`` of a point-based prim.

    Args:
        prim: A ``UsdGeom.PointBased`` prim.
        frames: The resampled recording.
        chosen: Indices of the recording's points that make the prim's ``points`` (repeats
            allowed), or ``None`` for all of them in order.
        half_width: Half the width [m] of each of the prim's points (or one for all), which
            the extent includes as UsdGeom's extent rules ask.
    """
    from pxr import Vt

    points, extent = prim.CreatePointsAttr(), prim.CreateExtentAttr()

    def write(k: int) -> None:
        positions = frames.points_at(k)
        if chosen is not None:
            positions = positions[chosen]
        points.Set(Vt.Vec3fArray.FromNumpy(positions.astype(np.float32)), k)
        extent.Set(Vt.Vec3fArray.FromNumpy(_extent(positions, half_width)), k)

    return write


def _add_points(stage: Any, frames: ExportFrames, loose: np.ndarray) -> Callable[[int], None]:
    from pxr import UsdGeom, Vt

    prim = UsdGeom.Points.Define(stage, "/World/points")
    widths = prim.CreateWidthsAttr()
    prim.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    look = frames.look
    colour = None
    if look.color is not None:
        colour = prim.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
    if not (frames.lifecycle or look.varying_radius or look.varying_color):
        radius = frames.radius_at(0)[loose]
        widths.Set(Vt.FloatArray.FromNumpy((2.0 * radius).astype(np.float32)))
        if colour is not None and look.color is not None:
            colour.Set(Vt.Vec3fArray.FromNumpy(look.color[loose]))
        chosen = None if loose.size == frames.point_count else loose
        return _animate(prim, frames, chosen, radius)
    return _animate_points(prim, frames, loose, widths, colour)


def _animate_points(
    prim: Any, frames: ExportFrames, loose: np.ndarray, widths: Any, colour: Any
) -> Callable[[int], None]:
    """A writer of every per-frame attribute of ``/World/points``: only the live points."""
    from pxr import Vt

    points, extent = prim.CreatePointsAttr(), prim.CreateExtentAttr()
    ids = prim.CreateIdsAttr() if frames.lifecycle else None
    on_loose = np.zeros(frames.point_count, dtype=bool)
    on_loose[loose] = True

    def write(k: int) -> None:
        chosen = np.flatnonzero(on_loose & frames.alive_at(k))
        positions = frames.points_at(k)[chosen]
        radius = frames.radius_at(k)[chosen]
        points.Set(Vt.Vec3fArray.FromNumpy(positions.astype(np.float32)), k)
        widths.Set(Vt.FloatArray.FromNumpy((2.0 * radius).astype(np.float32)), k)
        extent.Set(Vt.Vec3fArray.FromNumpy(_extent(positions, radius)), k)
        if ids is not None:
            ids.Set(Vt.Int64Array.FromNumpy(chosen.astype(np.int64)), k)
        rgb = frames.color_at(k)
        if colour is not None and rgb is not None:
            colour.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(rgb[chosen])), k)

    return write


def _add_edges(stage: Any, frames: ExportFrames, edges: np.ndarray) -> Callable[[int], None]:
    from pxr import UsdGeom, Vt

    prim = UsdGeom.BasisCurves.Define(stage, "/World/edges")
    prim.CreateTypeAttr(UsdGeom.Tokens.linear)
    prim.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
    counts = np.full(edges.shape[0], 2, dtype=np.int32)
    prim.CreateCurveVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    radius = frames.look.radius
    thinnest = float(radius[radius > 0.0].min()) if (radius > 0.0).any() else None
    width = _EDGE_WIDTH_FRACTION * 2.0 * (thinnest or frames.geometry.default_radius())
    prim.CreateWidthsAttr(Vt.FloatArray([width]))
    prim.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    return _animate(prim, frames, edges.ravel(), width / 2.0)


def _add_mesh(stage: Any, frames: ExportFrames, faces: np.ndarray) -> Callable[[int], None]:
    from pxr import UsdGeom, Vt

    prim = UsdGeom.Mesh.Define(stage, "/World/mesh")
    counts = np.full(faces.shape[0], 3, dtype=np.int32)
    prim.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    # Only the points the faces use, renumbered in order: a point on no face would become a
    # stray vertex of the mesh (those are /World/points already).
    used, renumbered = np.unique(faces, return_inverse=True)
    indices = renumbered.reshape(faces.shape).ravel().astype(np.int32)
    prim.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    prim.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    prim.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    prim.CreateDoubleSidedAttr(True)
    return _animate(prim, frames, None if used.size == frames.point_count else used, 0.0)


def _prim_names(names: tuple[str, ...]) -> list[str]:
    """``names`` as valid prim names (``Tf.MakeValidIdentifier``), made unique by a suffix."""
    from pxr import Tf

    chosen: list[str] = []
    for name in names:
        base = Tf.MakeValidIdentifier(name)
        unique, n = base, 1
        while unique in chosen:
            unique, n = f"{base}_{n}", n + 1
        chosen.append(unique)
    return chosen


def _add_bodies(stage: Any, frames: ExportFrames, bodies: BodyGeometry) -> Callable[[int], None]:
    """One ``Xform`` per rigid body with a static mesh of its surface; a writer of the
    transforms' time samples."""
    from pxr import Gf, UsdGeom, Vt

    UsdGeom.Xform.Define(stage, "/World/bodies")
    ops = []
    for b, name in enumerate(_prim_names(bodies.names)):
        xform = UsdGeom.Xform.Define(stage, f"/World/bodies/{name}")
        ops.append(
            (
                xform.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble),
                xform.AddOrientOp(UsdGeom.XformOp.PrecisionDouble),
            )
        )
        # The mesh takes the body's name too: Blender merges an Xform with its one child mesh
        # into one object named after the child ("surface.001" ... helps no one).
        mesh = UsdGeom.Mesh.Define(stage, f"/World/bodies/{name}/{name}")
        vertices, triangles = bodies.surface(b)
        first, last = bodies.vertex_start[b], bodies.vertex_start[b + 1]
        counts = np.full(triangles.shape[0], 3, dtype=np.int32)
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(vertices.astype(np.float32)))
        mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(_extent(vertices, 0.0)))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(triangles.ravel().astype(np.int32)))
        normals = bodies.normals[first:last].astype(np.float32)
        mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(normals))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        colour = mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant)
        colour.Set(Vt.Vec3fArray([Gf.Vec3f(*bodies.color[b].tolist())]))

    def write(k: int) -> None:
        position, orientation = frames.body_transforms_at(k)
        for (translate, orient), x, q in zip(
            ops, position.tolist(), orientation.tolist(), strict=True
        ):
            translate.Set(Gf.Vec3d(*x), k)
            orient.Set(Gf.Quatd(q[0], Gf.Vec3d(q[1], q[2], q[3])), k)

    return write


def _add_scenery(stage: Any, scenery: Scenery) -> None:
    """One static mesh per drawn collider, in the world frame (no time samples)."""
    from pxr import Gf, UsdGeom, Vt

    UsdGeom.Scope.Define(stage, "/World/scenery")
    for c, name in enumerate(_prim_names(scenery.names)):
        mesh = UsdGeom.Mesh.Define(stage, f"/World/scenery/{name}")
        vertices, triangles = scenery.surface(c)
        first, last = scenery.vertex_start[c], scenery.vertex_start[c + 1]
        counts = np.full(triangles.shape[0], 3, dtype=np.int32)
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(vertices.astype(np.float32)))
        mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(_extent(vertices, 0.0)))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(triangles.ravel().astype(np.int32)))
        mesh.CreateNormalsAttr(
            Vt.Vec3fArray.FromNumpy(scenery.normals[first:last].astype(np.float32))
        )
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        colour = mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant)
        colour.Set(Vt.Vec3fArray([Gf.Vec3f(*scenery.color[c].tolist())]))


def write_usd(frames: ExportFrames, path: Path, *, encoding: str) -> list[Path]:
    """Write the resampled recording as a USD stage (see the module docstring), atomically.

    Args:
        frames: The resampled recording (:func:`visviva.io.export._frames.prepare`).
        path: Target file ending in ``.usd``, ``.usda`` or ``.usdc``; its directory must
            exist. An existing file is replaced.
        encoding: ``"usda"`` (text) or ``"usdc"`` (binary crate), one of :data:`USD_ENCODINGS`.

    Returns:
        ``[path]``.
    """
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(frames.fps)
    stage.SetFramesPerSecond(frames.fps)
    stage.SetStartTimeCode(0.0)
    stage.SetEndTimeCode(float(frames.count - 1))
    first = float(frames.time[0])
    stage.GetRootLayer().documentation = (
        f"visviva {__version__} export of {frames.name!r}: {frames.count} frames at "
        f"{frames.fps:.9g} frames/s; time code k is {first!r} s + k·{frames.speed:.9g}/"
        f"{frames.fps:.9g} s of the simulation; metres, Y up"
    )
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())

    writers = []
    loose = frames.loose_points(faces=True)
    if loose.size:
        writers.append(_add_points(stage, frames, loose))
    if frames.edges is not None:
        writers.append(_add_edges(stage, frames, frames.edges))
    if frames.faces is not None:
        writers.append(_add_mesh(stage, frames, frames.faces))
    if frames.bodies is not None:
        writers.append(_add_bodies(stage, frames, frames.bodies))
    if frames.geometry.scenery is not None:
        _add_scenery(stage, frames.geometry.scenery)
    for k in range(frames.count):
        for write in writers:
            write(k)

    # A ".usd" file may hold either encoding: say which; ".usda"/".usdc" name their own.
    arguments = {"format": encoding} if path.suffix.lower() == ".usd" else {}
    with all_or_nothing([path]) as (temporary,):
        if not stage.GetRootLayer().Export(str(temporary), args=arguments):
            raise OSError(f"usd-core could not write {temporary}")
    return [path]
