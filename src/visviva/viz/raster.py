"""Drawing kernels of the video renderer: triangles, lines and spheres with a z-buffer.

Every kernel writes into a colour buffer ``color`` (float32, shape ``(H, W, 3)``, values in
``[0, 1]``) and a depth buffer ``depth`` (float32, shape ``(H, W)``, view depth [m] along the
camera's forward axis, ``inf`` where nothing is drawn). Screen coordinates are pixels with the
origin at the top-left corner of the image and y pointing down; pixel ``(i, j)`` (row, column)
has its centre at ``(j + 0.5, i + 0.5)``.

* :func:`draw_triangles` — Gouraud-shaded triangles set up with edge functions (Pineda 1988),
  perspective-correct: ``1/z`` and attributes over ``z`` are linear in screen space.
* :func:`draw_lines` — anti-aliased thick lines (capsules in screen space), depth-tested.
* :func:`draw_spheres` — sphere impostors: each sphere is a disc whose per-pixel normal is that
  of the sphere's visible hemisphere, ``n = (u, v, sqrt(1 − u² − v²))`` in view space, lit by
  hemispheric ambient + Lambert + a Blinn-Phong highlight (Blinn 1977), depth
  ``z_c − r·n_z``, with an anti-aliased rim (coverage from the distance to the silhouette).
* :func:`splat_points` — many small points added up as light (a star field): each a Gaussian
  spot whose brightness adds to what is there, no depth test; :func:`expose` maps the sum of
  light to colour as film does, ``1 − exp(−E)``, so dense regions glow instead of clipping.
* :func:`to_bytes` — the finished frame as 8-bit RGB.

The sky, the ground and the shadows are in :mod:`visviva.viz.ground`. All kernels are plain
loops compiled by Numba, one thread each: ffmpeg encodes on the other core meanwhile.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Variance [px²] of a star field's Gaussian spot: 0.8 px standard deviation.
SPOT = 0.64

__all__ = ["draw_lines", "draw_spheres", "draw_triangles", "expose", "splat_points", "to_bytes"]


@njit(cache=True)
def draw_triangles(
    color: np.ndarray,
    depth: np.ndarray,
    screen: np.ndarray,
    faces: np.ndarray,
    light_front: np.ndarray,
    light_back: np.ndarray,
    rgb_front: np.ndarray,
    rgb_back: np.ndarray,
    near: float,
) -> None:
    """Gouraud-shaded, depth-tested triangles; each side has its own colour.

    Args:
        color, depth: Buffers to draw into.
        screen: Vertex screen x, y [px] and view depth [m], shape ``(V, 3)``.
        faces: Vertex indices, counter-clockwise seen from the front, shape ``(F, 3)``.
        light_front, light_back: Light factor of each vertex on the front and back side,
            shape ``(V,)``.
        rgb_front, rgb_back: Colour of the front and back side, shape ``(3,)``.
        near: Triangles with a vertex nearer than this [m] are skipped.
    """
    height, width = depth.shape
    for f in range(faces.shape[0]):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        x0, y0, z0 = screen[a, 0], screen[a, 1], screen[a, 2]
        x1, y1, z1 = screen[b, 0], screen[b, 1], screen[b, 2]
        x2, y2, z2 = screen[c, 0], screen[c, 1], screen[c, 2]
        if not (z0 > near and z1 > near and z2 > near):
            continue
        area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        if area == 0.0 or not math.isfinite(area):
            continue
        # With y pointing down, counter-clockwise seen by the viewer has negative area.
        front = area < 0.0
        shade = light_front if front else light_back
        rgb = rgb_front if front else rgb_back
        inverse = 1.0 / area
        col0 = max(0, math.floor(min(x0, x1, x2)))
        col1 = min(width, math.ceil(max(x0, x1, x2)) + 1)
        row0 = max(0, math.floor(min(y0, y1, y2)))
        row1 = min(height, math.ceil(max(y0, y1, y2)) + 1)
        for i in range(row0, row1):
            py = i + 0.5
            for j in range(col0, col1):
                px = j + 0.5
                w0 = ((x2 - x1) * (py - y1) - (y2 - y1) * (px - x1)) * inverse
                w1 = ((x0 - x2) * (py - y2) - (y0 - y2) * (px - x2)) * inverse
                w2 = ((x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)) * inverse
                if w0 < 0.0 or w1 < 0.0 or w2 < 0.0:
                    continue
                p0, p1, p2 = w0 / z0, w1 / z1, w2 / z2
                total = p0 + p1 + p2
                z = 1.0 / total
                if z >= depth[i, j]:
                    continue
                light = (p0 * shade[a] + p1 * shade[b] + p2 * shade[c]) * z
                depth[i, j] = z
                for channel in range(3):
                    color[i, j, channel] = rgb[channel] * light


@njit(cache=True)
def _line_pixel(
    color: np.ndarray,
    depth: np.ndarray,
    i: int,
    j: int,
    segment: np.ndarray,
    half_width: float,
    rgb: np.ndarray,
    bias: float,
) -> None:
    x0, y0, z0, x1, y1, z1 = segment[0], segment[1], segment[2], segment[3], segment[4], segment[5]
    px, py = j + 0.5, i + 0.5
    dx, dy = x1 - x0, y1 - y0
    length2 = dx * dx + dy * dy
    s = 0.0 if length2 == 0.0 else ((px - x0) * dx + (py - y0) * dy) / length2
    s = min(1.0, max(0.0, s))
    ex, ey = px - x0 - s * dx, py - y0 - s * dy
    coverage = min(1.0, half_width + 0.5 - math.sqrt(ex * ex + ey * ey))
    if coverage <= 0.0:
        return
    # 1/z is linear in screen space; the bias keeps lines on top of the faces they border.
    z = (1.0 - bias) / ((1.0 - s) / z0 + s / z1)
    if z >= depth[i, j]:
        return
    for channel in range(3):
        color[i, j, channel] += coverage * (rgb[channel] - color[i, j, channel])
    if coverage > 0.5:
        depth[i, j] = z


@njit(cache=True)
def draw_lines(
    color: np.ndarray,
    depth: np.ndarray,
    segments: np.ndarray,
    half_width: float,
    rgb: np.ndarray,
    bias: float,
) -> None:
    """Anti-aliased, depth-tested lines with round caps.

    Args:
        color, depth: Buffers to draw into.
        segments: Per line ``x0, y0, z0, x1, y1, z1``: screen x, y [px] and view depth [m] of
            both ends (already clipped to the near plane), shape ``(E, 6)``.
        half_width: Half the line width [px].
        rgb: Line colour, shape ``(3,)``.
        bias: Relative depth bias pulling lines towards the camera (e.g. 1e-3).
    """
    height, width = depth.shape
    reach = half_width + 1.0
    # A column (or row) of a line of slope ≤ 1 spans at most √2·half_width + 1/2 pixels.
    extent = 1.5 * reach
    for e in range(segments.shape[0]):
        x0, y0, x1, y1 = segments[e, 0], segments[e, 1], segments[e, 3], segments[e, 4]
        dx, dy = x1 - x0, y1 - y0
        if not (math.isfinite(dx) and math.isfinite(dy)):
            continue
        if abs(dx) >= abs(dy):
            lo = max(0, math.floor(min(x0, x1) - reach))
            hi = min(width, math.ceil(max(x0, x1) + reach) + 1)
            for j in range(lo, hi):
                s = 0.0 if dx == 0.0 else min(1.0, max(0.0, (j + 0.5 - x0) / dx))
                middle = y0 + s * dy
                for i in range(
                    max(0, math.floor(middle - extent)),
                    min(height, math.ceil(middle + extent) + 1),
                ):
                    _line_pixel(color, depth, i, j, segments[e], half_width, rgb, bias)
        else:
            lo = max(0, math.floor(min(y0, y1) - reach))
            hi = min(height, math.ceil(max(y0, y1) + reach) + 1)
            for i in range(lo, hi):
                s = min(1.0, max(0.0, (i + 0.5 - y0) / dy))
                middle = x0 + s * dx
                for j in range(
                    max(0, math.floor(middle - extent)),
                    min(width, math.ceil(middle + extent) + 1),
                ):
                    _line_pixel(color, depth, i, j, segments[e], half_width, rgb, bias)


@njit(cache=True)
def _gloss(cosine: float) -> float:
    """Blinn-Phong highlight ``cosine**32``, by five squarings (a float power costs far more)."""
    value = cosine * cosine
    value *= value
    value *= value
    value *= value
    return value * value


@njit(cache=True)
def _sphere_box(centre: float, size: float, limit: int) -> tuple[int, int]:
    """Pixel range ``[start, stop)`` along one axis touched by a disc (rim included)."""
    return max(0, math.floor(centre - size - 0.5)), min(limit, math.ceil(centre + size + 0.5) + 1)


@njit(cache=True)
def _sphere_depths(
    depth: np.ndarray,
    screen: np.ndarray,
    radius: np.ndarray,
    radius_px: np.ndarray,
    order: np.ndarray,
) -> None:
    """Depth pre-pass: the depth of every fully covered sphere pixel, nearest spheres first.

    With the final depths known, the colour pass shades only the pixels that stay visible
    instead of every pixel of every sphere (in a dense cloud, most are hidden).
    """
    height, width = depth.shape
    for n in range(order.size - 1, -1, -1):
        k = order[n]
        size = radius_px[k]
        if not size >= 1.0:  # smaller discs have no fully covered pixel worth the pass
            continue
        cx, cy, cz = screen[k, 0], screen[k, 1], screen[k, 2]
        row0, row1 = _sphere_box(cy, size, height)
        col0, col1 = _sphere_box(cx, size, width)
        inverse = 1.0 / size
        full = (1.0 - 0.5 * inverse) ** 2  # inside this, the coverage is 1
        for i in range(row0, row1):
            v = (cy - (i + 0.5)) * inverse
            for j in range(col0, col1):
                u = (j + 0.5 - cx) * inverse
                q = u * u + v * v
                if q <= full:
                    z = np.float32(cz - radius[k] * math.sqrt(1.0 - q))
                    if z < depth[i, j]:
                        depth[i, j] = z


@njit(cache=True)
def draw_spheres(
    color: np.ndarray,
    depth: np.ndarray,
    screen: np.ndarray,
    radius: np.ndarray,
    radius_px: np.ndarray,
    order: np.ndarray,
    rgb: np.ndarray,
    light: np.ndarray,
    material: np.ndarray,
    min_px: float,
) -> None:
    """Shaded, depth-tested sphere impostors with anti-aliased rims, drawn in ``order``.

    Args:
        color, depth: Buffers to draw into.
        screen: Sphere centre screen x, y [px] and view depth [m], shape ``(P, 3)``.
        radius: Sphere radii [m], shape ``(P,)``.
        radius_px: Apparent radii [px], shape ``(P,)``; spheres with NaN or 0 are skipped.
        order: Indices of the spheres to draw, far to near so rims blend over what is behind.
        rgb: Colour of each sphere, shape ``(P, 3)``.
        light: Rows: direction towards the light, world up, Blinn half vector, all in view
            coordinates (x right, y up, z towards the viewer), shape ``(3, 3)``.
        material: Ambient from below, ambient from above, diffuse, specular (shininess 32).
        min_px: Spheres smaller than this [px] are drawn at this size, fainter, so that
            distant particles neither vanish nor flicker.
    """
    height, width = depth.shape
    below, above, diffuse, specular = material[0], material[1], material[2], material[3]
    lx, ly, lz = light[0, 0], light[0, 1], light[0, 2]
    ux, uy, uz = light[1, 0], light[1, 1], light[1, 2]
    hx, hy, hz = light[2, 0], light[2, 1], light[2, 2]
    _sphere_depths(depth, screen, radius, radius_px, order)
    for k in order:
        size = radius_px[k]
        if not size > 0.0:
            continue
        opacity = 1.0
        if size < min_px:
            opacity = (size / min_px) ** 2
            size = min_px
        cx, cy, cz = screen[k, 0], screen[k, 1], screen[k, 2]
        red, green, blue = rgb[k, 0], rgb[k, 1], rgb[k, 2]
        row0, row1 = _sphere_box(cy, size, height)
        col0, col1 = _sphere_box(cx, size, width)
        inverse = 1.0 / size
        # Pixels beyond the rim's outer half pixel are rejected before any square root.
        reach = (1.0 + 0.5 * inverse) ** 2
        r_k = radius[k]
        for i in range(row0, row1):
            v = (cy - (i + 0.5)) * inverse  # view y points up, rows point down
            for j in range(col0, col1):
                u = (j + 0.5 - cx) * inverse
                q = u * u + v * v
                if q >= reach:
                    continue
                if q < 1.0:
                    nx, ny, nz = u, v, math.sqrt(1.0 - q)
                    z = np.float32(cz - r_k * nz)
                else:  # the rim's outer half pixel: a normal on the silhouette
                    scale = 1.0 / math.sqrt(q)
                    nx, ny, nz = u * scale, v * scale, 0.0
                    z = np.float32(cz)
                # Equal passes: the pre-pass wrote this very depth for the visible sphere.
                if z > depth[i, j]:
                    continue
                coverage = min(1.0, size * (1.0 - math.sqrt(q)) + 0.5) * opacity
                lambert = max(0.0, nx * lx + ny * ly + nz * lz)
                upward = nx * ux + ny * uy + nz * uz
                lit = below + (above - below) * (0.5 + 0.5 * upward) + diffuse * lambert
                gloss = specular * _gloss(max(0.0, nx * hx + ny * hy + nz * hz))
                pixel = color[i, j]
                pixel[0] += coverage * (red * lit + gloss - pixel[0])
                pixel[1] += coverage * (green * lit + gloss - pixel[1])
                pixel[2] += coverage * (blue * lit + gloss - pixel[2])
                if coverage > 0.5:
                    depth[i, j] = z


@njit(cache=True)
def splat_points(
    light: np.ndarray, screen: np.ndarray, order: np.ndarray, colour: np.ndarray, gain: float
) -> None:
    """Add each point ``order[k]`` at ``screen[order[k], :2]`` [px] to ``light`` (float32
    ``(H, W, 3)``) as a Gaussian spot of variance :data:`SPOT` [px²] (4 × 4 pixels), of total
    brightness ``gain`` times its colour ``colour[order[k]]``; points off screen or behind the
    camera (NaN) add nothing."""
    height, width = light.shape[0], light.shape[1]
    for k in range(order.shape[0]):
        p = order[k]
        x, y = screen[p, 0], screen[p, 1]
        if not (x == x and y == y) or x < -2.0 or y < -2.0 or x > width + 2.0 or y > height + 2.0:
            continue
        j0, i0 = math.floor(x - 0.5), math.floor(y - 0.5)
        for i in range(i0 - 1, i0 + 3):
            if i < 0 or i >= height:
                continue
            dy = i + 0.5 - y
            for j in range(j0 - 1, j0 + 3):
                if j < 0 or j >= width:
                    continue
                dx = j + 0.5 - x
                weight = (
                    gain * math.exp(-(dx * dx + dy * dy) / (2.0 * 0.64)) / (2.0 * math.pi * 0.64)
                )
                for channel in range(3):
                    light[i, j, channel] += weight * colour[p, channel]


@njit(cache=True)
def expose(light: np.ndarray, color: np.ndarray) -> None:
    """``color ← color + (1 − color)·(1 − exp(−light))``, in place: light added to a dark
    background as film takes it, saturating smoothly where many points overlap."""
    height, width = light.shape[0], light.shape[1]
    for i in range(height):
        for j in range(width):
            for channel in range(3):
                base = color[i, j, channel]
                color[i, j, channel] = base + (1.0 - base) * (1.0 - math.exp(-light[i, j, channel]))


@njit(cache=True)
def to_bytes(color: np.ndarray, out: np.ndarray) -> None:
    """Write ``color`` (values in [0, 1]) to ``out`` as 8-bit RGB, rounded and clipped."""
    height, width = out.shape[0], out.shape[1]
    for i in range(height):
        for j in range(width):
            for channel in range(3):
                value = color[i, j, channel] * 255.0 + 0.5
                out[i, j, channel] = min(255.0, max(0.0, value))
