"""Files in and out: recordings (HDF5)."""

from .recording import (
    FORMAT,
    FORMAT_VERSION,
    Geometry,
    Recording,
    read_recordings,
    write_recordings,
)

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "Geometry",
    "Recording",
    "read_recordings",
    "write_recordings",
]
