"""The video's light: where it comes from, the surfaces' material, and per-vertex shading.

One home for what every shaded layer of :mod:`visviva.viz.frame` shares (the faces of cloth,
the rigid bodies of :mod:`visviva.viz.body_layer`, the spheres' kernel arguments): a light
from above, hemispheric ambient (darker from below than from above) plus Lambert diffuse.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LIGHT", "MATERIAL", "lit_sides"]

#: Direction towards the light (world frame, Y up): from above, a little from the left front.
LIGHT = np.array([-0.3, 1.0, 0.35]) / np.linalg.norm([-0.3, 1.0, 0.35])
#: Ambient light from below and from above, diffuse, specular (Blinn-Phong exponent 32).
MATERIAL = (0.30, 0.52, 0.62, 0.30)


def lit_sides(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Light factors of vertices with unit world ``normal`` ``(V, 3)``, seen from the side
    the normal points to and from the other: two ``(V,)`` arrays, ambient plus diffuse."""
    below, above, diffuse = MATERIAL[0], MATERIAL[1], MATERIAL[2]
    sides = []
    for sign in (1.0, -1.0):
        n = sign * normal
        ambient = below + (above - below) * (0.5 + 0.5 * n[:, 1])
        sides.append(ambient + diffuse * np.maximum(n @ LIGHT, 0.0))
    return sides[0], sides[1]
