"""The ground and the sky of the video renderer, and shadows on the ground.

The camera does not move during a clip, so :func:`paint_background` runs once: it supersamples
the sky gradient and the checkered ground plane (``samples²`` rays per pixel, which also
anti-aliases the checker and the horizon), and records for every pixel its view depth and the
point (x, z) where its centre ray meets the ground.

Shadows, every frame, in two steps that cost O(objects + pixels) whatever the number of
spheres: the layers *splat* what blocks the light into an occlusion map, a grid lying on the
ground (:func:`splat_discs` for spheres, :func:`splat_triangles` for faces; both are first
moved along the light onto the ground), and :func:`compose_ground` starts the frame from the
background, darkened where each pixel's ground point reads occlusion from the map (bilinear
interpolation; the map's cells are a fraction of a sphere's radius, so shadows come out as
soft blobs). A directional light and a shadow map in the plane of the receiver is the classic
projected-shadow construction (Blinn 1988, "Me and my (fake) shadow").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["compose_ground", "paint_background", "splat_discs", "splat_triangles"]


@njit(cache=True)
def _environment(
    eye: np.ndarray,
    dx: float,
    dy: float,
    dz: float,
    ground_y: float,
    cell: float,
    fog: float,
    palette: np.ndarray,
) -> tuple[float, float, float, float]:
    """Colour seen along the ray ``eye + t·d`` and its parameter ``t`` (inf for the sky).

    ``palette`` rows: sky at the zenith, sky at the horizon, ground tone A, ground tone B.
    """
    if eye[1] > ground_y and dy < 0.0:
        t = (ground_y - eye[1]) / dy
        hx = eye[0] + t * dx
        hz = eye[2] + t * dz
        tone = 2 + (math.floor(hx / cell) + math.floor(hz / cell)) % 2
        # Haze towards the horizon hides the checker's aliasing and gives depth.
        distance = t * math.sqrt(dx * dx + dy * dy + dz * dz)
        haze = 1.0 - math.exp(-((distance / fog) ** 2))
        r = palette[tone, 0] + haze * (palette[1, 0] - palette[tone, 0])
        g = palette[tone, 1] + haze * (palette[1, 1] - palette[tone, 1])
        b = palette[tone, 2] + haze * (palette[1, 2] - palette[tone, 2])
        return r, g, b, t
    elevation = max(0.0, dy / math.sqrt(dx * dx + dy * dy + dz * dz))
    mix = math.sqrt(elevation)
    r = palette[1, 0] + mix * (palette[0, 0] - palette[1, 0])
    g = palette[1, 1] + mix * (palette[0, 1] - palette[1, 1])
    b = palette[1, 2] + mix * (palette[0, 2] - palette[1, 2])
    return r, g, b, math.inf


@njit(cache=True)
def paint_background(
    color: np.ndarray,
    depth: np.ndarray,
    ground_x: np.ndarray,
    ground_z: np.ndarray,
    eye: np.ndarray,
    basis: np.ndarray,
    focal: float,
    ground_y: float,
    cell: float,
    fog: float,
    palette: np.ndarray,
    samples: int,
) -> None:
    """Sky and ground, ``samples × samples`` rays per pixel; ground hit point per pixel centre.

    Args:
        color, depth: Buffers to fill.
        ground_x, ground_z: Filled with the world x, z [m] where each pixel's centre ray meets
            the ground, NaN for the sky; shape ``(H, W)``.
        eye: Camera position [m], shape ``(3,)``.
        basis: Rows right, up, forward of the camera (world frame), shape ``(3, 3)``.
        focal: Focal length [px].
        ground_y: Height of the ground plane [m].
        cell: Side of a checker square [m].
        fog: Distance over which the ground fades to the horizon colour [m].
        palette: Sky zenith, sky horizon, ground tones A and B (RGB in [0, 1]), shape ``(4, 3)``.
        samples: Rays per pixel along each axis.
    """
    height, width = depth.shape
    half_w, half_h = 0.5 * width, 0.5 * height
    for i in range(height):
        for j in range(width):
            r = g = b = 0.0
            for si in range(samples + 1):
                for sj in range(samples):
                    # The last pass is the pixel centre, used for depth and the ground hit only.
                    if si == samples:
                        if sj > 0:
                            break
                        px, py = j + 0.5, i + 0.5
                    else:
                        px, py = j + (sj + 0.5) / samples, i + (si + 0.5) / samples
                    a, c = (px - half_w) / focal, (half_h - py) / focal
                    dx = basis[2, 0] + a * basis[0, 0] + c * basis[1, 0]
                    dy = basis[2, 1] + a * basis[0, 1] + c * basis[1, 1]
                    dz = basis[2, 2] + a * basis[0, 2] + c * basis[1, 2]
                    sr, sg, sb, t = _environment(eye, dx, dy, dz, ground_y, cell, fog, palette)
                    if si == samples:
                        # The ray's forward component is 1, so t is the view depth itself.
                        depth[i, j] = t
                        ground_x[i, j] = eye[0] + t * dx if t < math.inf else math.nan
                        ground_z[i, j] = eye[2] + t * dz if t < math.inf else math.nan
                    else:
                        r += sr
                        g += sg
                        b += sb
            scale = 1.0 / (samples * samples)
            color[i, j, 0] = r * scale
            color[i, j, 1] = g * scale
            color[i, j, 2] = b * scale


@njit(cache=True)
def _add(occlusion: np.ndarray, i: int, j: int, amount: float) -> None:
    if 0 <= i < occlusion.shape[0] and 0 <= j < occlusion.shape[1]:
        occlusion[i, j] += amount


@njit(cache=True)
def splat_discs(
    occlusion: np.ndarray,
    origin: np.ndarray,
    cell: float,
    centre: np.ndarray,
    radius: np.ndarray,
    weight: np.ndarray,
) -> None:
    """Add discs lying on the ground to the occlusion map.

    Args:
        occlusion: Light blocked per cell (0 = none, ≥ 1 = all), shape ``(nz, nx)``; cell
            ``(i, j)`` spans x from ``origin[0] + j·cell`` and z from ``origin[1] + i·cell``.
        origin: World (x, z) [m] of the map's corner.
        cell: Side of a cell [m].
        centre: Disc centres (x, z) [m], shape ``(n,)`` × 2.
        radius: Disc radii [m], shape ``(n,)``.
        weight: How much light each disc blocks, in [0, 1], shape ``(n,)``.
    """
    rows, columns = occlusion.shape
    inverse = 1.0 / cell
    for k in range(centre.shape[0]):
        # Continuous coordinates in which cell (i, j) has its centre at (j, i).
        u = (centre[k, 0] - origin[0]) * inverse - 0.5
        v = (centre[k, 1] - origin[1]) * inverse - 0.5
        size = radius[k] * inverse
        if not (math.isfinite(u) and math.isfinite(v) and size > 0.0):
            continue
        if size < 1.0:
            # Smaller than a cell: its area, shared bilinearly by the four nearest cells.
            amount = weight[k] * math.pi * size * size
            j0, i0 = math.floor(u), math.floor(v)
            fu, fv = u - j0, v - i0
            _add(occlusion, i0, j0, amount * (1.0 - fu) * (1.0 - fv))
            _add(occlusion, i0, j0 + 1, amount * fu * (1.0 - fv))
            _add(occlusion, i0 + 1, j0, amount * (1.0 - fu) * fv)
            _add(occlusion, i0 + 1, j0 + 1, amount * fu * fv)
            continue
        for i in range(max(0, math.floor(v - size)), min(rows, math.ceil(v + size) + 1)):
            for j in range(max(0, math.floor(u - size)), min(columns, math.ceil(u + size) + 1)):
                inside = size + 0.5 - math.sqrt((j - u) ** 2 + (i - v) ** 2)
                if inside > 0.0:
                    occlusion[i, j] += weight[k] * min(1.0, inside)


@njit(cache=True)
def splat_triangles(
    occlusion: np.ndarray, origin: np.ndarray, cell: float, corners: np.ndarray, weight: float
) -> None:
    """Add triangles lying on the ground to the occlusion map (cells whose centre is inside).

    Args:
        occlusion, origin, cell: As in :func:`splat_discs`.
        corners: Triangle corners (x, z) [m], shape ``(F, 3, 2)``, either orientation.
        weight: How much light a triangle blocks, in [0, 1].
    """
    rows, columns = occlusion.shape
    inverse = 1.0 / cell
    for f in range(corners.shape[0]):
        ax, az = (corners[f, 0, 0] - origin[0]) * inverse, (corners[f, 0, 1] - origin[1]) * inverse
        bx, bz = (corners[f, 1, 0] - origin[0]) * inverse, (corners[f, 1, 1] - origin[1]) * inverse
        cx, cz = (corners[f, 2, 0] - origin[0]) * inverse, (corners[f, 2, 1] - origin[1]) * inverse
        if not (math.isfinite(ax + az + bx + bz + cx + cz)):
            continue
        for i in range(max(0, math.floor(min(az, bz, cz))), min(rows, math.ceil(max(az, bz, cz)))):
            pz = i + 0.5
            for j in range(
                max(0, math.floor(min(ax, bx, cx))), min(columns, math.ceil(max(ax, bx, cx)))
            ):
                px = j + 0.5
                e0 = (bx - ax) * (pz - az) - (bz - az) * (px - ax)
                e1 = (cx - bx) * (pz - bz) - (cz - bz) * (px - bx)
                e2 = (ax - cx) * (pz - cz) - (az - cz) * (px - cx)
                if (e0 >= 0.0 and e1 >= 0.0 and e2 >= 0.0) or (
                    e0 <= 0.0 and e1 <= 0.0 and e2 <= 0.0
                ):
                    occlusion[i, j] += weight


@njit(cache=True)
def compose_ground(
    color: np.ndarray,
    depth: np.ndarray,
    background: np.ndarray,
    background_depth: np.ndarray,
    ground_x: np.ndarray,
    ground_z: np.ndarray,
    occlusion: np.ndarray,
    origin: np.ndarray,
    cell: float,
    darkness: float,
) -> None:
    """Start a frame: the background, darkened by the occlusion map where it shows the ground.

    Args:
        color, depth: The frame's buffers, overwritten.
        background, background_depth, ground_x, ground_z: From :func:`paint_background`.
        occlusion, origin, cell: The occlusion map (see :func:`splat_discs`).
        darkness: Fraction of the light removed where the occlusion is 1 or more.
    """
    height, width = depth.shape
    rows, columns = occlusion.shape
    inverse = 1.0 / cell
    for i in range(height):
        for j in range(width):
            depth[i, j] = background_depth[i, j]
            lit = 1.0
            u = (ground_x[i, j] - origin[0]) * inverse - 0.5
            v = (ground_z[i, j] - origin[1]) * inverse - 0.5
            # False for NaN (the sky) and outside the map.
            if 0.0 <= u < columns - 1 and 0.0 <= v < rows - 1:
                j0, i0 = int(u), int(v)
                fu, fv = u - j0, v - i0
                blocked = (1.0 - fv) * (
                    (1.0 - fu) * occlusion[i0, j0] + fu * occlusion[i0, j0 + 1]
                ) + fv * ((1.0 - fu) * occlusion[i0 + 1, j0] + fu * occlusion[i0 + 1, j0 + 1])
                lit = 1.0 - darkness * min(1.0, blocked)
            for channel in range(3):
                color[i, j, channel] = background[i, j, channel] * lit
