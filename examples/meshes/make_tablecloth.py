"""Writes tablecloth.obj: a round tablecloth of radius 0.5 m, lying flat 1 m up (y up), as a mesh of
nearly equilateral triangles — a centre vertex and rings of 6, 12, 18, ... vertices, each ring
joined to the one inside it by a strip of triangles. Run from anywhere:
``python examples/meshes/make_tablecloth.py``."""

from __future__ import annotations

import math
from pathlib import Path

RADIUS = 0.5  # [m]
RINGS = 8  # rings around the centre: 1 + 3·8·9 = 217 vertices, 6·8² = 384 triangles
HEIGHT = 1.0  # [m]: a scene uses a mesh file's coordinates as they are, in metres


def ring(k: int) -> list[tuple[float, float, float]]:
    """Ring ``k``'s 6k points (the centre for k = 0), counter-clockwise seen from above."""
    if k == 0:
        return [(0.0, HEIGHT, 0.0)]
    r = RADIUS * k / RINGS
    angles = [2 * math.pi * j / (6 * k) for j in range(6 * k)]
    return [(r * math.cos(a), HEIGHT, -r * math.sin(a)) for a in angles]


def strip(inner: list[int], outer: list[int]) -> list[tuple[int, int, int]]:
    """Triangles joining two closed rings of vertex indices, both starting at angle 0: walk
    round both, each time advancing on the ring whose next vertex comes first."""
    triangles = []
    i = j = 0
    m, n = len(inner), len(outer)
    while i < m or j < n:
        if j < n and (i == m or (j + 1) / n <= (i + 1) / m):
            triangles.append((inner[i % m], outer[j], outer[(j + 1) % n]))
            j += 1
        else:
            triangles.append((inner[i % m], outer[j % n], inner[(i + 1) % m]))
            i += 1
    return triangles


def main() -> None:
    vertices: list[tuple[float, float, float]] = []
    rings: list[list[int]] = []
    for k in range(RINGS + 1):
        points = ring(k)
        rings.append(list(range(len(vertices), len(vertices) + len(points))))
        vertices += points
    triangles = [(0, rings[1][j], rings[1][(j + 1) % 6]) for j in range(6)]
    for k in range(2, RINGS + 1):
        triangles += strip(rings[k - 1], rings[k])
    lines = [
        "# A round tablecloth, radius 0.5 m, flat 1 m up (y up): written by make_tablecloth.py",
        *("v " + " ".join(f"{round(c, 6) + 0.0:.6f}" for c in v) for v in vertices),  # no "-0"
        *(f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles),
    ]
    (Path(__file__).parent / "tablecloth.obj").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
