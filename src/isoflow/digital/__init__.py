"""Digital geometry of voxel objects (sections 2-4 and 6 of the paper): the
lattice and the digital object, vertex configurations, curvature indices,
Euler characteristic, Betti numbers, simple points, the boundary quad mesh
as arrays, the shape report, n-dimensional tables.

Imports only :mod:`isoflow.scale` (and :mod:`isoflow.errors`).
See docs/architecture.md.
"""
