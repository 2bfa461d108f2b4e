"""The digital curvature flow (section 5 of the paper): the moves of a step
(3D and planar), topology control, running a flow, its files and pictures.

Imports :mod:`isoflow.digital`, :mod:`isoflow.mesh` and :mod:`isoflow.scale`.
See docs/architecture.md.
"""
