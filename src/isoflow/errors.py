"""The one exception type isoflow raises for bad input.

The CLI turns it into a one-line message and exit code 2; the Python API lets
it propagate. Its message always names the thing that is wrong (file, field,
value) so that nobody has to read a traceback from inside numpy.
"""


class IsoflowError(ValueError):
    """Bad input: a missing or unreadable file, an empty or open mesh, ...

    Its message is one line that names the file, the field or the value.

    Examples
    --------
    >>> import isoflow
    >>> try:
    ...     isoflow.read_volume("no-such-volume.npy")
    ... except IsoflowError as exc:
    ...     print(exc)
    no-such-volume.npy: no such file
    """


class IsoflowWarning(UserWarning):
    """Something a user should know that is not an error: a file format that
    cannot keep the voxel size, an affine's rotation left out. The command
    line prints it as one ``warning:`` line."""


class MeshNote(IsoflowWarning):
    """What is unusual about a mesh that was voxelised, and the rule that
    read it (double-sided faces, boundary edges, an empty solid and the
    fill that gives the model): the ``note`` of
    :class:`~isoflow.mesh.voxelize.Voxelization`, issued as a warning
    when the caller did not ask for the details. The command line prints it
    as one ``note:`` line."""
