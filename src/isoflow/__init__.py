"""isoflow: digital geometry between voxels and polygon surfaces.

Implements A. Imiya, *Curvature and Flow in Digital Space* (2013): curvature
indices of lattice vertices (section 4), the digital Gauss-Bonnet theorem
(Theorems 10-11, exact form ``a^T n = 8 chi``), the boundary quad mesh of a
voxel object, and the digital curvature flow (section 5).

The core is array in / array out; :class:`DigitalObject` only adds where the
array sits (offset, lattice parity, pitch, origin).
"""

from . import arrays
from .analysis import analyze
from .configurations import configuration_histogram
from .errors import IsoflowError
from .indices import (
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
from .io import read_object, read_points, read_volume, write_volume
from .flow import FlowResult, flow_step, run_flow
from .lattice import DigitalObject
from .meshes import from_manifold, to_manifold, verify_genus, voxelize_file, voxelize_mesh
from .surface import QuadMesh, boundary_mesh
from .topology import betti_numbers, euler_characteristic

__version__ = "0.1.0"

__all__ = [
    "CLASS_LABELS",
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
