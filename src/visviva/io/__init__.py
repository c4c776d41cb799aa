"""Files in and out: recordings (HDF5), scene files, exports."""

from .recording import (
    FORMAT,
    FORMAT_VERSION,
    load_recording,
    read_recordings,
    save_recording,
    write_recordings,
)

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "load_recording",
    "read_recordings",
    "save_recording",
    "write_recordings",
]
