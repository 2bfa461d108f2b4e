"""Files and polygon meshes: reading meshes, volumes and point lists,
voxelising meshes, writing the boundary mesh, the manifold3d and pymeshlab
bridges, genus verification, pictures of surfaces.

Imports :mod:`isoflow.digital` and :mod:`isoflow.scale`; trimesh, manifold3d,
pymeshlab and matplotlib are imported inside the functions that need them.
See docs/architecture.md.
"""
