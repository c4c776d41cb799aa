"""Exporting recordings for Blender, Houdini and other tools: USD, glTF 2.0, OBJ sequences, PC2.

:func:`export_recording` is the one entry point (the ``visviva export`` command calls it). It
checks everything first: the format, the target path, the recording's geometry and the frame
rate; then one writer module writes the files, each atomically (see ``_files.py``):

==========  ============================================================================
``usd``     :mod:`.usd`: time-sampled ``Points`` / ``BasisCurves`` / ``Mesh`` under ``/World``,
            an ``Xform`` with time-sampled translate and orient per rigid body
``glb``     :mod:`.gltf`: a mesh with one morph target per frame and a STEP weight animation,
            or sphere nodes; a node per rigid body with translation and rotation channels
``obj``     :mod:`.obj`: one Wavefront OBJ file per frame (rigid bodies placed, a group each)
``pc2``     :mod:`.pc2`: a point cache for Blender's Mesh Cache modifier and 3ds Max
==========  ============================================================================

Every format shows output frame ``k`` at ``k/fps`` seconds after the first recorded frame,
using the recorded frame :func:`visviva.io.timeline.frames_at_rate` picks. Positions are in
metres, Y up, as recorded; ``docs/export.md`` shows how to import each file. Particles that are
born and die (a recording's ``alive``) never appear as points while dead: USD and OBJ write only
the live points of each frame, glTF hides dead ones (a sphere scaled to 0, or a vertex moved
onto a live point), PC2 holds them where they were last alive (see each writer's module).
Rigid bodies (:mod:`visviva.simulation.body_geometry`) are a surface each and a transform per
frame: USD and glTF write the transforms and a static mesh, OBJ and PC2 the placed vertices.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..._registry import did_you_mean
from ..._validation import describe
from ...errors import ModelError
from ...simulation.recording import Recording
from ._frames import FALLBACK_FPS, MAX_OUTPUT_FRAMES, default_fps, prepare

__all__ = [
    "EXPORT_FORMATS",
    "FALLBACK_FPS",
    "MAX_OUTPUT_FRAMES",
    "default_fps",
    "export_recording",
]

#: Export format → one-line description (for ``visviva export --help``).
EXPORT_FORMATS: dict[str, str] = {
    "usd": "USD stage (.usd/.usdc binary, .usda text): time-sampled points, curves, mesh, bodies",
    "usda": "USD stage as text (.usda, or .usd)",
    "usdc": "USD stage as binary crate (.usdc, or .usd)",
    "glb": "glTF 2.0 binary (.glb): morph targets or sphere nodes; body nodes' transforms",
    "gltf": "glTF 2.0 (.gltf JSON with a .bin beside it, or .glb binary)",
    "obj": "Wavefront OBJ sequence, one file per frame (NAME_0000.obj... or DIR/frame_0000.obj)",
    "pc2": "PC2 point cache (.pc2) for Blender's Mesh Cache modifier and 3ds Max",
}

#: Suffixes each file format accepts (lower case); OBJ takes ``.obj`` or a directory.
_SUFFIXES: dict[str, tuple[str, ...]] = {
    "usd": (".usd", ".usda", ".usdc"),
    "usda": (".usda", ".usd"),
    "usdc": (".usdc", ".usd"),
    "glb": (".glb",),
    "gltf": (".gltf", ".glb"),
    "pc2": (".pc2",),
}
#: Format chosen from a suffix when ``to`` is not given.
_BY_SUFFIX = {
    ".usd": "usd",
    ".usda": "usd",
    ".usdc": "usd",
    ".glb": "glb",
    ".gltf": "gltf",
    ".obj": "obj",
    ".pc2": "pc2",
}


def _valid_formats() -> str:
    return ", ".join(EXPORT_FORMATS)


def _resolve_format(path: Path, to: str | None) -> str:
    """The format to write: ``to``, or the one ``path``'s suffix names; checked against it."""
    suffix = path.suffix.lower()
    if to is None:
        if suffix not in _BY_SUFFIX:
            raise ModelError(
                f"cannot tell the export format from `path` {os.fspath(path)!r} (suffix "
                f"{suffix or 'none'}); pass to= one of: {_valid_formats()}, or use a suffix "
                f"{', '.join(_BY_SUFFIX)}"
            )
        return _BY_SUFFIX[suffix]
    if not isinstance(to, str):
        raise ModelError(
            f"`to` must be a format name (got {describe(to)}); valid: {_valid_formats()}"
        )
    if to not in EXPORT_FORMATS:
        raise ModelError(
            f"unknown export format `to` = {to!r}.{did_you_mean(to.lower(), EXPORT_FORMATS)} "
            f"Valid: {_valid_formats()}"
        )
    if to == "obj":
        # ".obj" names the files' prefix, anything else a directory, unless the suffix is
        # another format's (a slip more likely than a directory named "rope.glb").
        if suffix != ".obj" and suffix in _BY_SUFFIX:
            raise ModelError(
                f"`path` {os.fspath(path)!r} names a {_BY_SUFFIX[suffix]} file, not an OBJ "
                f"sequence: use a path ending in .obj (e.g. "
                f"{os.fspath(path.with_suffix('.obj'))!r}) or a directory"
            )
        return to
    accepted = _SUFFIXES[to]
    if suffix not in accepted:
        raise ModelError(
            f"`path` {os.fspath(path)!r} does not end in {' or '.join(accepted)}, as a {to} "
            f"file must; use e.g. {os.fspath(path.with_suffix(accepted[0]))!r}"
        )
    return to


def _check_target(path: Path, fmt: str) -> None:
    """Refuse a target whose directory is missing, or a file target that is a directory."""
    directory_output = fmt == "obj" and path.suffix.lower() != ".obj"
    parent = path.parent
    if not parent.is_dir():
        raise ModelError(
            f"`path` {os.fspath(path)!r}: directory {os.fspath(parent)!r} does not exist; "
            "create it first"
        )
    if directory_output:
        if path.exists() and not path.is_dir():
            raise ModelError(
                f"`path` {os.fspath(path)!r} is a file, but an OBJ sequence needs a directory "
                "(or a path ending in .obj for NAME_0000.obj files next to it)"
            )
    elif path.is_dir():
        example = "animation" + _SUFFIXES.get(fmt, (".obj",))[0]
        raise ModelError(
            f"`path` {os.fspath(path)!r} is a directory; give a file name such as "
            f"{os.fspath(path / example)!r}"
        )


def export_recording(
    recording: Recording,
    path: str | os.PathLike[str],
    *,
    to: str | None = None,
    fps: float | None = None,
    speed: float = 1.0,
) -> list[Path]:
    """Export a recording's geometry as USD, glTF 2.0, an OBJ sequence or a PC2 point cache.

    Args:
        recording: A recording with a ``points`` field (and optionally ``radius``, ``edges``,
            ``faces``), rigid bodies, or both (see :meth:`visviva.Recording.geometry`).
        path: Target file. Its suffix chooses the format when ``to`` is not given and must
            fit it when it is (:data:`EXPORT_FORMATS`). For ``obj``, a path ending in ``.obj``
            gets ``STEM_0000.obj`` … next to it; any other path is a directory (created if
            missing) that gets ``frame_0000.obj`` …. Its directory must exist. Existing files
            of the same names are replaced (the command line asks for ``--force`` first).
        to: ``"usd"``, ``"usda"``, ``"usdc"``, ``"glb"``, ``"gltf"``, ``"obj"`` or ``"pc2"``;
            default: from the suffix of ``path``. ``"usd"`` writes binary to ``.usd`` and
            ``.usdc`` and text to ``.usda``; ``"gltf"`` writes JSON plus ``.bin`` to ``.gltf``
            and binary to ``.glb``.
        fps: Output frames per second [1/s]; output frame ``k`` shows the recorded frame
            nearest ``t0 + k/fps``. Default: the recording's own rate if its frames are evenly
            spaced, else :data:`FALLBACK_FPS` (see :func:`default_fps`).
        speed: Simulated seconds per second of playback (output frame ``k`` shows the
            recorded frame nearest ``t0 + k·speed/fps``): 86400 plays a day per second.

    Returns:
        The files written, in order (one, or one per frame for OBJ, or ``.gltf`` and ``.bin``).

    Raises:
        ModelError: Before anything is written, for an unknown format, a suffix that does not
            fit it, a missing directory, a recording without points or bodies, an invalid
            ``fps``, a non-finite position or body transform, or a glTF buffer over
            :data:`visviva.io.export.gltf.MAX_GLTF_BYTES`.

    Example:
        >>> import tempfile, numpy as np, visviva as vv
        >>> from visviva.io.export import export_recording
        >>> t = np.arange(5) / 10.0                          # 5 frames at 10 Hz
        >>> pts = np.zeros((5, 2, 3)); pts[:, 1, 1] = t      # point 1 rises at 1 m/s
        >>> rec = vv.Recording(t, {"particle_position": pts}, units={"particle_position": "m"})
        >>> folder = tempfile.mkdtemp()
        >>> [p.name for p in export_recording(rec, f"{folder}/rise.pc2", fps=20.0)]
        ['rise.pc2']
        >>> [p.name for p in export_recording(rec, f"{folder}/rise.obj")][-1]
        'rise_0004.obj'
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ModelError(f"`path` must be a file path (got {describe(path)})")
    target = Path(path)
    fmt = _resolve_format(target, to)
    _check_target(target, fmt)
    frames = prepare(recording, fps, speed)
    suffix = target.suffix.lower()
    if fmt in ("usd", "usda", "usdc"):
        from .usd import write_usd

        encoding = fmt if fmt != "usd" else ("usda" if suffix == ".usda" else "usdc")
        return write_usd(frames, target, encoding=encoding)
    if fmt in ("glb", "gltf"):
        from .gltf import write_gltf

        return write_gltf(frames, target, binary=suffix == ".glb")
    if fmt == "obj":
        from .obj import write_obj_sequence

        return write_obj_sequence(frames, target)
    from .pc2 import write_pc2

    return write_pc2(frames, target)
