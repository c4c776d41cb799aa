"""Geometry shared by the physics packages: mesh topology checks (closed, oriented, outward),
self-intersection and inside tests, unit quaternions for orientations, and the neighbour grid
(which points lie within a radius of which, every step) that every pairwise interaction shares."""
