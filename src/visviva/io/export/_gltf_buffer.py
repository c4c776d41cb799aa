"""The binary buffer of a glTF 2.0 export: views, accessors and colours (Khronos glTF 2.0,
§ 3.6 "Buffers, buffer views and accessors", § 3.9 "Materials").

Shared by the layouts of :mod:`.gltf` and the rigid bodies of :mod:`._gltf_rigid`: each part
appends its arrays to one :class:`GltfBuffer` and keeps the accessor indices it gets back.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["GltfBuffer", "linear_rgb"]


class GltfBuffer:
    """The binary buffer with its views and accessors, filled part by part."""

    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.views: list[Any] = []
        self.accessors: list[Any] = []
        self.size = 0

    def view(self, data: np.ndarray, **options: Any) -> int:
        import pygltflib as gl

        raw = np.ascontiguousarray(data).tobytes()
        self.views.append(
            gl.BufferView(buffer=0, byteOffset=self.size, byteLength=len(raw), **options)
        )
        self.parts.append(raw)
        self.size += len(raw)  # every part is whole 4-byte values: the next stays aligned
        return len(self.views) - 1

    def accessor(self, **fields: Any) -> int:
        import pygltflib as gl

        self.accessors.append(gl.Accessor(**fields))
        return len(self.accessors) - 1

    def floats(self, values: np.ndarray, kind: str, *, bounds: bool = False, **view: Any) -> int:
        """An accessor of float32 ``values`` (``(count,)`` SCALAR, ``(count, 3)`` VEC3 or
        ``(count, 4)`` VEC4)."""
        import pygltflib as gl

        values = np.asarray(values, dtype="<f4")
        extremes: dict[str, Any] = {}
        if bounds:
            rows = values.reshape(len(values), -1)
            extremes = {"min": rows.min(axis=0).tolist(), "max": rows.max(axis=0).tolist()}
        return self.accessor(
            bufferView=self.view(values, **view),
            componentType=gl.FLOAT,
            count=len(values),
            type=kind,
            **extremes,
        )

    def indices(self, values: np.ndarray) -> int:
        import pygltflib as gl

        return self.accessor(
            bufferView=self.view(np.asarray(values, dtype="<u4"), target=gl.ELEMENT_ARRAY_BUFFER),
            componentType=gl.UNSIGNED_INT,
            count=int(values.size),
            type=gl.SCALAR,
        )

    def blob(self) -> bytes:
        return b"".join(self.parts)


def linear_rgb(srgb: np.ndarray) -> np.ndarray:
    """sRGB values in [0, 1] as linear ones (IEC 61966-2-1), which glTF colours are."""
    srgb = np.asarray(srgb, dtype=np.float64)
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
