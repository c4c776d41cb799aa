"""Geometry shared by the physics packages: mesh topology checks (closed, oriented, outward),
self-intersection and inside tests, and unit quaternions for orientations."""
