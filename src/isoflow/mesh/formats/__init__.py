"""Volume file formats, one module each, found by suffix through
:mod:`isoflow.mesh.formats.registry` (imports nothing, like every
sub-package ``__init__``)."""
