"""isoflow: digital geometry between voxels and polygon surfaces.

Implements A. Imiya, *Curvature and Flow in Digital Space* (2013): curvature
indices of lattice vertices (section 4), the digital Gauss-Bonnet theorem
(Theorems 10-11, exact form ``a^T n = 8 chi``), the boundary quad mesh of a
voxel object, and the digital curvature flow (section 5).

The core is array in / array out; :class:`DigitalObject` only adds where the
array sits (offset, lattice parity, pitch, origin).
"""

from .digital.analysis import analyze
from .digital.configurations import configuration_histogram
from .digital.indices import (
    CLASS_LABELS,
    a_lut,
    class_histogram,
    class_lut,
    code_lut,
    f_lut,
    gamma_lut,
    normal_lut,
    planar_index,
)
from .digital.lattice import DigitalObject
from .digital.outofcore import analyze_chunked, analyze_zarr
from .digital.surface import QuadMesh, boundary_mesh
from .digital.topology import betti_numbers, euler_characteristic
from .errors import IsoflowError
from .flow.motion import flow_step
from .flow.run import FlowResult, run_flow
from .mesh.bridges import from_manifold, to_manifold
from .mesh.genus import verify_genus
from .mesh.volumes import read_object, read_points, read_volume, write_volume
from .mesh.voxelize import voxelize_file, voxelize_mesh

__version__ = "0.1.0"

__all__ = [
    "CLASS_LABELS",
    "analyze_chunked",
    "analyze_zarr",
    "DigitalObject",
    "FlowResult",
    "flow_step",
    "from_manifold",
    "run_flow",
    "to_manifold",
    "verify_genus",
    "voxelize_file",
    "voxelize_mesh",
    "IsoflowError",
    "QuadMesh",
    "a_lut",
    "analyze",
    "betti_numbers",
    "boundary_mesh",
    "class_histogram",
    "class_lut",
    "code_lut",
    "configuration_histogram",
    "euler_characteristic",
    "f_lut",
    "gamma_lut",
    "normal_lut",
    "planar_index",
    "read_object",
    "read_points",
    "read_volume",
    "write_volume",
]
