"""isoflow: digital geometry between voxels and polygon surfaces.

Implements A. Imiya, *Curvature and Flow in Digital Space* (2013): curvature
indices of lattice vertices (section 4), the digital Gauss-Bonnet theorem
(Theorems 10-11, exact form ``a^T n = 8 chi``), the boundary quad mesh of a
voxel object, and the digital curvature flow (section 5).

The core is array in / array out; :class:`DigitalObject` only adds where the
array sits (offset, lattice parity, pitch, origin).
"""

from importlib import import_module

# The public API, loaded on first use (PEP 562): ``import isoflow`` and the
# command line then pay only for the modules a command needs (``isoflow
# info`` never loads the voxeliser, the flow or the mesh bridges).
_WHERE = {
    "analyze": ".digital.analysis",
    "configuration_histogram": ".digital.configurations",
    "CLASS_LABELS": ".digital.indices",
    "a_lut": ".digital.indices",
    "class_histogram": ".digital.indices",
    "class_lut": ".digital.indices",
    "code_lut": ".digital.indices",
    "f_lut": ".digital.indices",
    "gamma_lut": ".digital.indices",
    "normal_lut": ".digital.indices",
    "planar_index": ".digital.indices",
    "DigitalObject": ".digital.lattice",
    "label_table": ".digital.label_table",
    "analyze_chunked": ".digital.outofcore",
    "analyze_zarr": ".digital.outofcore",
    "QuadMesh": ".digital.surface",
    "boundary_mesh": ".digital.surface",
    "closed_surfaces": ".digital.closed_surfaces",
    "betti_numbers": ".digital.topology",
    "euler_characteristic": ".digital.topology",
    "IsoflowError": ".errors",
    "flow_step": ".flow.motion",
    "FlowResult": ".flow.run",
    "run_flow": ".flow.run",
    "from_manifold": ".mesh.bridges",
    "to_manifold": ".mesh.bridges",
    "verify_genus": ".mesh.genus",
    "read_object": ".mesh.volumes",
    "read_points": ".mesh.volumes",
    "read_volume": ".mesh.volumes",
    "write_volume": ".mesh.volumes",
    "voxelize_file": ".mesh.voxelize",
    "voxelize_mesh": ".mesh.voxelize",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(_WHERE[name], __name__), name)
        globals()[name] = value  # the next lookup is a plain attribute
        return value
    raise AttributeError(f"module 'isoflow' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_WHERE))


__version__ = "0.1.0"

__all__ = sorted(_WHERE)  # every public name, as the table above gives it
