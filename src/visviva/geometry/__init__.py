"""Geometry shared by the physics packages: mesh topology checks (closed, oriented, outward)."""
