"""Files in and out: recordings (HDF5), scene files, exports."""

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
    "dump_scene",
    "load_recording",
    "load_scene",
    "parse_scene",
    "read_recordings",
    "save_recording",
    "write_recordings",
]
