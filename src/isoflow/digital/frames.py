"""Anatomical frames: where a volume's world axes +x, +y, +z point, as a
three-letter code (``"RAS"``: x to the patient's Right, y Anterior, z
Superior), so that a volume read in one format's frame (NRRD's LPS, as 3D
Slicer and ITK write) is written in another's (NIfTI's and MGH's RAS)
without mirroring the patient. :func:`space_given` checks a code that a
:class:`~isoflow.digital.lattice.DigitalObject` or a writer is given;
:func:`axes_against` names the world axes a writer negates to change frame,
:func:`grid_in_frame` negates them in a grid's steps and voxel 0's centre;
:func:`frame_text` says a frame in words.
"""

from __future__ import annotations

import numpy as np

from ..errors import IsoflowError

#: the two directions each world axis may point, in x, y, z order: a code
#: takes one letter of each pair in turn (a permuted code such as "ASR"
#: would reorder the axes, which a per-axis sign cannot say)
AXIS_LETTERS = ("RL", "AP", "SI")
#: the directions of :data:`AXIS_LETTERS` in words, letter by letter
AXIS_WORDS = (("right", "left"), ("anterior", "posterior"), ("superior", "inferior"))


def space_given(space: object, where: str) -> str | None:
    """An anatomical frame as its three-letter code in capitals, None for
    None; one line naming it where it is no such code.

    Parameters
    ----------
    space : str or None
        Where +x, +y, +z point: ``R`` or ``L``, then ``A`` or ``P``, then
        ``S`` or ``I`` (``"RAS"``, ``"LPS"``, ``"LAS"``, ...), in any case.
    where : str
        What a refusal names (the object, the file).

    Returns
    -------
    str or None
        The code in capitals.

    Raises
    ------
    IsoflowError
        Where ``space`` is not such a code.

    Examples
    --------
    >>> space_given("lps", "a.nii"), space_given(None, "a.nii") is None
    ('LPS', True)
    >>> space_given("scanner-xyz", "a.nii")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: a.nii: space 'scanner-xyz' is not an anatomical frame (three letters: R or L, \
A or P, S or I, as 'RAS' or 'LPS')
    """
    if space is None:
        return None
    code = space.upper() if isinstance(space, str) else None
    if code is None or len(code) != 3 or any(c not in pair for c, pair in zip(code, AXIS_LETTERS)):
        raise IsoflowError(f"{where}: space {space!r} is not an anatomical frame (three letters: R or L, A or P, S or "
                           "I, as 'RAS' or 'LPS')")
    return code


def frame_text(space: str) -> str:
    """The anatomical frame ``space`` in words, for a warning.

    Parameters
    ----------
    space : str
        A three-letter code (:func:`space_given`).

    Returns
    -------
    str

    Examples
    --------
    >>> frame_text("LPS")
    'the frame LPS (x to the left, y posterior, z superior)'
    """
    x, y, z = (words[pair.index(c)] for c, pair, words in zip(space, AXIS_LETTERS, AXIS_WORDS))
    return f"the frame {space} (x to the {x}, y {y}, z {z})"


def axes_against(space: str, frame: str = "RAS") -> list[int]:
    """The world axes along which ``space`` points opposite to ``frame``:
    a coordinate in ``space`` is negated along them to give the same
    anatomical place in ``frame``.

    Parameters
    ----------
    space, frame : str
        Three-letter codes (:func:`space_given`).

    Returns
    -------
    list of int
        Axis numbers, 0 for x.

    Examples
    --------
    A point 10 mm to the patient's left is at x = 10 in LPS and at
    x = -10 in RAS:

    >>> axes_against("LPS"), axes_against("LAS"), axes_against("LPS", "LPS")
    ([0, 1], [0], [])
    """
    return [axis for axis, (a, b) in enumerate(zip(space, frame)) if a != b]


def grid_in_frame(steps: np.ndarray, centre0: np.ndarray, space: str,
                  frame: str = "RAS") -> tuple[np.ndarray, np.ndarray]:
    """A grid's world steps and voxel 0's centre, given in ``space``, in
    ``frame``: each world axis that points the other way
    (:func:`axes_against`; only those the grid has) negated, so that every
    voxel keeps its anatomical place.

    Parameters
    ----------
    steps : numpy.ndarray
        Row ``i``: the world step of array axis ``i`` (a column per world
        axis).
    centre0 : numpy.ndarray
        Voxel 0's centre, one entry per world axis.
    space, frame : str
        Three-letter codes (:func:`space_given`).

    Returns
    -------
    steps, centre0 : numpy.ndarray
        New arrays; a coordinate of 0 stays 0.0, not -0.0.

    Examples
    --------
    >>> steps, centre0 = grid_in_frame(np.diag([0.5, 0.5, 2.0]), np.array([9.5, 0.0, 1.0]), "LPS")
    >>> steps.diagonal().tolist(), centre0.tolist()
    ([-0.5, -0.5, 2.0], [-9.5, 0.0, 1.0])
    """
    flipped = [axis for axis in axes_against(space, frame) if axis < len(centre0)]
    steps, centre0 = np.array(steps, np.float64), np.array(centre0, np.float64)
    steps[:, flipped] = 0.0 - steps[:, flipped]  # (0.0 - x keeps a 0 as 0.0; * -1 would give -0.0)
    centre0[flipped] = 0.0 - centre0[flipped]
    return steps, centre0
