"""Files in and out: recordings (HDF5), scene files, meshes, exports."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .meshes import MeshFileError, read_triangle_mesh
    from .recording import (
        FORMAT,
        FORMAT_VERSION,
        load_recording,
        read_recordings,
        save_recording,
        write_recordings,
    )
    from .scene_files import dump_scene, load_scene, parse_scene

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "MeshFileError",
    "dump_scene",
    "load_recording",
    "load_scene",
    "parse_scene",
    "read_recordings",
    "read_triangle_mesh",
    "save_recording",
    "write_recordings",
]

# Names load on first use (visviva._lazy): a job that writes recordings does not need the
# scene files' parser and pydantic models, nor a scene file the recordings.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "FORMAT": "recording",
        "FORMAT_VERSION": "recording",
        "load_recording": "recording",
        "read_recordings": "recording",
        "save_recording": "recording",
        "write_recordings": "recording",
        "dump_scene": "scene_files",
        "load_scene": "scene_files",
        "parse_scene": "scene_files",
        "MeshFileError": "meshes",
        "read_triangle_mesh": "meshes",
    },
)
