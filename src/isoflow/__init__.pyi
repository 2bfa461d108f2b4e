"""The public API with its types (the lazy loader of ``__init__.py`` gives
the same names at run time; tests/test_public_api.py holds the two equal)."""

from . import data as data
from .digital.analysis import analyze as analyze
from .digital.closed_surfaces import closed_surfaces as closed_surfaces
from .digital.configurations import (
    configuration_histogram as configuration_histogram,
)
from .digital.configurations import (
    configurations as configurations,
)
from .digital.indices import (
    CLASS_LABELS as CLASS_LABELS,
)
from .digital.indices import (
    a_lut as a_lut,
)
from .digital.indices import (
    class_histogram as class_histogram,
)
from .digital.indices import (
    class_lut as class_lut,
)
from .digital.indices import (
    code_lut as code_lut,
)
from .digital.indices import (
    euler_lut as euler_lut,
)
from .digital.indices import (
    f_lut as f_lut,
)
from .digital.indices import (
    gamma_lut as gamma_lut,
)
from .digital.indices import (
    normal_lut as normal_lut,
)
from .digital.indices import (
    planar_index as planar_index,
)
from .digital.label_table import LabelImage as LabelImage
from .digital.label_table import label_table as label_table
from .digital.lattice import DigitalObject as DigitalObject
from .digital.outofcore import analyze_chunked as analyze_chunked
from .digital.report import ClosedSurface as ClosedSurface
from .digital.report import ClosedSurfaces as ClosedSurfaces
from .digital.report import Report as Report
from .digital.surface import QuadMesh as QuadMesh
from .digital.surface import boundary_mesh as boundary_mesh
from .digital.topology import betti_numbers as betti_numbers
from .digital.topology import euler_characteristic as euler_characteristic
from .errors import IsoflowError as IsoflowError
from .errors import IsoflowWarning as IsoflowWarning
from .flow.motion import flow_step as flow_step
from .flow.run import FlowResult as FlowResult
from .flow.run import run_flow as run_flow
from .mesh.bridges import from_manifold as from_manifold
from .mesh.bridges import to_manifold as to_manifold
from .mesh.export import write_surface as write_surface
from .mesh.formats.label_names import read_label_names as read_label_names
from .mesh.formats.omezarr import analyze_zarr as analyze_zarr
from .mesh.genus import verify_genus as verify_genus
from .mesh.label_voxels import voxelize_meshes as voxelize_meshes
from .mesh.slabs import voxelize_to_zarr as voxelize_to_zarr
from .mesh.verdict import GenusVerdict as GenusVerdict
from .mesh.volumes import (
    read_labels as read_labels,
)
from .mesh.volumes import (
    read_object as read_object,
)
from .mesh.volumes import (
    read_points as read_points,
)
from .mesh.volumes import (
    read_volume as read_volume,
)
from .mesh.volumes import (
    write_labels as write_labels,
)
from .mesh.volumes import (
    write_volume as write_volume,
)
from .mesh.voxelize import voxelize_file as voxelize_file
from .mesh.voxelize import voxelize_mesh as voxelize_mesh

__version__: str
__all__: list[str]
