"""The contacts of two posed convex shapes: an analytic path where there is one, else GJK/EPA
and the clipped manifold.

Two boxes (the commonest pair of a pile) go through the separating axes of
:mod:`~visviva.collision.box_box`; every other pair, and two boxes whose nearest features the
axes do not settle, through :func:`~visviva.collision.separation.shape_distance` and
:func:`~visviva.collision.manifold.contact_manifold`. Both give the same contacts to rounding
where the normal is unique (tested).
"""

from __future__ import annotations

from numba import njit

from .box_box import box_box_contacts
from .convex import BOX
from .manifold import contact_manifold
from .separation import shape_distance

__all__ = ["GJK_TOLERANCE", "convex_contacts"]

#: GJK's relative tolerance for contacts: a gap exact to this fraction of itself (a nanometre
#: on a millimetre's gap; the distance queries take 1e-13). On round cores GJK converges
#: linearly, and the last digits cost most of its iterations.
GJK_TOLERANCE = 1e-6


@njit(cache=True)
def convex_contacts(shape_a, shape_b, max_separation, points, depths, work):
    """Contacts of two posed convex shapes (:mod:`~visviva.collision.convex`) within
    ``max_separation`` [m]: ``(count, nx, ny, nz)``, the points and depths in the first
    ``count`` rows of ``points`` ``(CANDIDATES, 3)`` and ``depths``, as
    :func:`~visviva.collision.manifold.contact_manifold` gives them; ``work`` is
    :func:`~visviva.collision.box_box.clip_work`."""
    params_a, params_b = shape_a[1], shape_b[1]
    if shape_a[0] == BOX and shape_b[0] == BOX and params_a[0] == 0.0 and params_b[0] == 0.0:
        count, nx, ny, nz = box_box_contacts(shape_a[6], shape_a[7], params_a[1:4], shape_b[6],
                                             shape_b[7], params_b[1:4], max_separation, points,
                                             depths, work)  # fmt: skip
        if count >= 0:
            return count, nx, ny, nz
    separation = shape_distance(shape_a, shape_b, max_separation, GJK_TOLERANCE)
    return contact_manifold(shape_a, shape_b, separation, max_separation, points, depths)
