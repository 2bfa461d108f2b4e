"""The voxel grid laid over a mesh: pitch, origin and shape, and the memory
it needs.

Grid convention
---------------
Voxel ``(i, j, k)`` is the closed cube ``[origin + pitch*(i, j, k),
origin + pitch*(i+1, j+1, k+1)]`` and its centre is
``origin + pitch*(i + 0.5, j + 0.5, k + 0.5)``.  The grid is laid out from the
bounding box of the vertices the faces use, on every axis the same way::

    n_a      = max(1, ceil(extent_a / pitch))         (exactly R on the longest
                                                       axis for resolution=R)
    origin_a = centre_a - n_a * pitch / 2              (grid centred on the bbox)

so the grid always covers the bounding box, by less than one voxel of slack
per axis, split evenly on both sides; an extent that is a whole number of
pitches up to rounding (1e-9 of it, or a float32 step of the bounds of a
mesh stored in float32: :func:`float32_slack`) gets that number, so the
centres stay half a voxel off its axis-aligned faces.  With ``resolution=R`` the pitch is
``max(extent) / R``.  The returned volume is the whole grid: empty border
layers are **not** trimmed and no padding is added, so the shape depends only
on the bounding box and the pitch (reproducible, and ``origin`` keeps its
simple meaning).  Solids often touch the array border (an axis-aligned face
on the bounding box always has the outermost layer of centres inside); pad
with ``np.pad(volume, 1)`` and shift ``origin`` by ``-pitch`` before anything
that needs an empty frame (Euler numbers, connected components, surfaces).

Why centred: it is symmetric (a mesh and its mirror image give mirrored
volumes) and translation-invariant (the grid moves with the mesh).  Its one
bias: along an axis-aligned extent of e = (n - f) * pitch, 0 <= f < 1, all n
centred layers fall inside, so flat axis-aligned slabs gain up to one layer
(plate_holes.STL at 128 across: 6 layers for a plate 5.3 pitches thick,
+13 % volume).  Centre sampling has to round such a slab to 5 or 6 layers
either way; the test-suite checks generic shapes to 6 % of area * pitch.

Scale
-----
Results do not depend on the units: the grid arithmetic runs on the
coordinates multiplied by a power of two that brings the mesh to about unit
size (exact, see :func:`voxel_grid`), so a mesh at 1e-200 or 1e200 gives the voxels it
gives at 1, with no products underflowing to 0 or overflowing; the weld's
distances are taken the same way.  Only a mesh whose bounding-box extent
overflows the float range (coordinates near +-1.8e308 on both sides) is
refused.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from numbers import Real

import numpy as np

from ..errors import IsoflowError, called_words, given_text, number_text, scalar_given, whole_given
from ..scale import memory
from ..scale.memory import sized
from .load import mesh_bbox, used_vertices

#: Largest ``resolution=`` accepted (voxels along the longest side).
MAX_RESOLUTION = 2**31 - 1
#: ``pitch=`` may exceed the mesh's longest bounding-box side by at most this
#: factor (beyond it the whole mesh is far inside one voxel, and the rounding
#: error of the voxel centre, ~2**-53 pitch, nears the size of the mesh).
_MAX_PITCH_RATIO = 2.0**40


def fmt_count(n: int, sep: bool = True) -> str:
    """An exact integer (with thousands separators if ``sep``); scientific
    beyond 10^18.  Python ints: no overflow however large."""
    n = int(n)
    if n < 10**18:
        return f"{n:,}" if sep else str(n)
    from decimal import Decimal

    return format(Decimal(n), ".3e")  # exact rounding, no float conversion



def grid_refusal(caller: str, words: str) -> IsoflowError:
    """A refusal of ``pitch=`` or ``resolution=`` that names the function
    called (``caller``), and on the command line the ``voxelize`` command
    and its options.

    Parameters
    ----------
    caller : str
        The function called, as its message begins.
    words : str
        What is wrong, in the Python API's words (``pitch=1e+300 ...``).

    Returns
    -------
    IsoflowError
        With :attr:`~isoflow.errors.IsoflowError.command_line` naming
        ``--pitch`` and ``--resolution``.

    Examples
    --------
    >>> e = grid_refusal("voxelize_file", "give exactly one of pitch= or resolution=")
    >>> str(e), e.command_line
    ('voxelize_file: give exactly one of pitch= or resolution=', 'voxelize: give exactly one of --pitch or --resolution')
    """
    options = re.sub(r"\b(pitch|resolution)=(\S*)", lambda m: option_words(m.group(0)).rstrip(), words)
    return IsoflowError.worded(f"{caller}: {words}", f"voxelize: {options}")


def check_grid_request(pitch: object, resolution: object, caller: str = "voxelize") -> tuple[float | None, int | None]:
    """``(pitch, resolution)`` checked before any mesh is read: exactly one
    given, a pitch a positive finite real number (or one in a one-element
    array), a resolution a whole number from 1 to :data:`MAX_RESOLUTION`;
    anything else refused naming ``caller``.

    Parameters
    ----------
    pitch, resolution : object
        As given to the function called; one of them None.
    caller : str
        The function called, which the refusal names.

    Returns
    -------
    (float or None, int or None)
        The pitch as a float, the resolution as an int.

    Examples
    --------
    >>> check_grid_request(None, 4.0), check_grid_request([0.5], None)
    ((None, 4), (0.5, None))
    >>> check_grid_request(0, None, "voxelize_mesh")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: voxelize_mesh: pitch must be a positive finite number, got 0
    """
    if (pitch is None) == (resolution is None):
        raise grid_refusal(caller, "give exactly one of pitch= or resolution=")
    if resolution is not None:
        whole = whole_given(resolution)
        if whole is None or not 1 <= whole <= MAX_RESOLUTION:
            raise grid_refusal(caller, f"resolution must be an integer from 1 to {MAX_RESOLUTION}, "
                                       f"got {given_text(resolution)}")
        return None, whole
    # float() reads "0.5" and True as numbers: a pitch given as text or a bool is refused
    # by name, as a resolution is, not taken for the number it spells
    if isinstance(pitch, (np.ndarray, list, tuple)) and np.size(pitch) == 1 and np.ndim(pitch) == 1:
        # one number in a one-element array, as DigitalObject takes a pitch (float() refuses it)
        (pitch,) = pitch
    pitch = scalar_given(pitch)
    # a voxel size is a real number, as DigitalObject's pitch: float() also read
    # Decimal("0.5"), which DigitalObject and every other number argument refuse
    if isinstance(pitch, (str, bytes, bool, np.bool_)) or not isinstance(pitch, Real):
        raise grid_refusal(caller, f"pitch must be a positive number, got {given_text(pitch)}")
    try:
        number = float(pitch)
    except (TypeError, ValueError, OverflowError):
        raise grid_refusal(caller, f"pitch must be a positive number, got {given_text(pitch)}") from None
    if not (math.isfinite(number) and number > 0):
        raise grid_refusal(caller, f"pitch must be a positive finite number, got {number_text(pitch)}")
    return number, None


def voxel_grid(v: np.ndarray, f: np.ndarray, pitch, resolution):
    """Pitch, origin and shape of the grid (see the module docstring), and the
    scaled frame the arithmetic runs in.

    Returns ``(pitch, origin, shape, what, frame)`` with
    ``frame = (shift, e, origin_s, pitch_s)``: the scanline and the
    generalised winding number work on coordinates ``ldexp(x - shift, -e)``,
    where ``2**e`` is the power of two just above the longest side of the
    bounding box (so the mesh spans about one unit), ``origin_s`` and
    ``pitch_s`` being the grid in those units.  ``shift`` is zero except on an
    axis where the mesh lies a size or more from zero (:func:`local_shift`):
    there the vertices are taken relative to a multiple of ``2**e`` near them,
    exactly, so that the voxel centres are placed with the precision they
    have near the origin.  Multiplying by a power of two is exact, and rounded
    sums, products and quotients commute with it (barring overflow and
    underflow), so every comparison the scanline makes is bit-for-bit the one
    the unscaled arithmetic makes wherever that neither overflows nor
    underflows: results at ordinary scales are unchanged, a mesh scaled by a
    power of two gives identical voxels, and one scaled by 1e-200 or 1e200
    (whose edge-function products would underflow to 0 or overflow) gives
    the voxels of the unscaled mesh up to the rounding of the scaling itself.
    """
    pitch, res = check_grid_request(pitch, resolution)
    lo, hi, ext = mesh_bbox(v, f, "voxelize")
    longest = float(ext.max())
    if not longest > 0:
        raise IsoflowError("voxelize: mesh bounding box has zero size (all vertices coincide)")
    e = math.frexp(longest)[1]
    shift = local_shift(lo, hi, e)
    lo_s, hi_s = np.ldexp(lo - shift, -e), np.ldexp(hi - shift, -e)
    ext_s = np.ldexp(ext, -e)
    if res is not None:
        pitch_s = float(ext_s.max()) / res
        pitch = math.ldexp(pitch_s, e)
        what = f"resolution={res}"
        cells = ext_s / pitch_s
    else:
        assert pitch is not None
        if pitch > _MAX_PITCH_RATIO * longest:
            raise grid_refusal("voxelize", f"pitch={given_text(pitch)} is more than 2**40 times the mesh's size (longest "
                                       f"bounding-box side {longest:.6g}): the whole mesh would lie inside one voxel")
        pitch_s = math.ldexp(pitch, -e)  # may underflow: then the grid is refused as too big
        what = f"pitch={pitch!r}"
        with np.errstate(over="ignore"):
            cells = ext / pitch  # the exact quantities' ratio, correctly rounded
    slack = float32_slack(lo, hi, pitch)
    shape = []
    for a in range(3):
        if resolution is not None and ext[a] == longest:
            n = res
        else:
            c = float(cells[a])
            if math.isfinite(c) and c < 2.0**53:
                # a relative 1e-9 guard so that an extent that is an exact
                # multiple of the pitch up to rounding does not gain a voxel,
                # but never dropping more than 1e-6 of a voxel of extent (a
                # huge c would otherwise lose whole layers); bounds a file
                # stored in float32 may be a float32 step off
                n = max(1, math.ceil(c - max(min(1e-9 * c, 1e-6), float(slack[a]))))
            else:  # the true count, in Python ints (it is refused as too big)
                from fractions import Fraction

                n = math.ceil(Fraction(float(ext[a])) / Fraction(pitch))
        shape.append(int(n))
    if max(shape) < 2**62:
        centre_s = (lo_s + hi_s) / 2
        origin_s = centre_s - np.asarray(shape, dtype=np.float64) * pitch_s / 2
    else:  # no such grid can be allocated: check_grid_memory refuses it
        origin_s = np.full(3, np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        origin = np.ldexp(origin_s, e) + shift
    return float(pitch), origin.astype(np.float64), tuple(shape), what, (shift, e, origin_s, pitch_s)


def float32_slack(lo: np.ndarray, hi: np.ndarray, pitch: float) -> np.ndarray:
    """Per axis, how many voxels of ``pitch`` the extent ``hi - lo`` may
    overstate when both bounds are float32 (as an STL, or a PLY of
    ``float`` properties, stores them): one float32 step at the larger
    bound, at most 1e-3 of a voxel; zero where a bound is no float32.

    A part 304.8 long stored in float32 reads 304.8000183: at a pitch of
    1.5875 that is 192.0000115 voxels, and a 193rd voxel centred over the
    part would put every voxel centre on its two end faces.

    Parameters
    ----------
    lo, hi : numpy.ndarray
        The bounding box's corners, shape (3,).
    pitch : float
        The voxel size.

    Returns
    -------
    numpy.ndarray
        float64, shape (3,): the slack in voxels.

    Examples
    --------
    >>> s = float32_slack(np.zeros(3), np.array([304.8000183105469, 304.8, 1.0]), 1.5875)
    >>> bool(0 < s[0] < 1e-4), float(s[1])
    (True, 0.0)
    """
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        held = (lo.astype(np.float32) == lo) & (hi.astype(np.float32) == hi)
        step = np.spacing(np.maximum(np.abs(lo), np.abs(hi)).astype(np.float32)).astype(np.float64)
        slack = np.minimum(step / pitch, 1e-3)
    return np.where(held & np.isfinite(slack), slack, 0.0)


def local_shift(lo: np.ndarray, hi: np.ndarray, e: int) -> np.ndarray:
    """Per axis, a multiple of ``2**e`` that the vertices in ``[lo, hi]``
    are taken relative to: zero where the box lies within ``2**e`` of zero,
    else the multiple of ``2**e`` nearest zero beyond which the box lies.

    ``2**e`` is at least the longest side of the box, so every vertex minus
    the shift lies within ``2**(e+1)`` of zero and is a multiple of the
    vertex's own spacing (the shift, a multiple of ``2**e``, is one of it
    wherever that spacing is at most ``2**e``, and of ``2**e`` where it is
    more): the difference is representable, and so computed exactly.  A mesh
    translated by a multiple of ``2**e`` thus gives the same coordinates
    relative to its shift, hence the same voxels bit for bit.

    Parameters
    ----------
    lo, hi : ndarray (3,)
        The bounding box.
    e : int
        The exponent of the power of two just above its longest side.

    Returns
    -------
    ndarray (3,)
        The shift, float64.

    Examples
    --------
    >>> local_shift(np.array([1e15, -0.5, -1e6 - 3]), np.array([1e15 + 4, 3.0, -1e6]), 3).tolist()
    [1000000000000000.0, 0.0, -1000000.0]
    """
    shift = np.zeros(3)
    if e > 1023:  # 2**e beyond the float range: every coordinate lies within it of zero
        return shift
    unit = math.ldexp(1.0, e)
    for a in range(3):
        # fmod is exact, and so is the subtraction (its result, a multiple
        # of 2**e no larger than |lo|, is representable)
        if lo[a] >= unit:
            shift[a] = lo[a] - math.fmod(lo[a], unit)
        elif hi[a] <= -unit:
            shift[a] = hi[a] - math.fmod(hi[a], unit)
    return shift


def near_origin(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The vertices the faces use moved by the :func:`local_shift` of their
    bounding box (exactly: see there), the others as they are: the mesh
    where a grid finer than the float64 spacing of its coordinates can be
    laid, for what depends on the voxels alone and not on where they lie
    (Betti numbers).

    Parameters
    ----------
    v, f : ndarray
        The checked mesh (:func:`~isoflow.mesh.load.check_mesh`).

    Returns
    -------
    ndarray
        A new vertex array, or ``v`` itself where no axis is shifted.

    Examples
    --------
    >>> near_origin(np.array([[1e15, 0, 0], [1e15 + 4, 1, 1], [7.0, 7, 7]]), np.array([[0, 1, 1]])).tolist()
    [[0.0, 0.0, 0.0], [4.0, 1.0, 1.0], [7.0, 7.0, 7.0]]
    """
    lo, hi, ext = mesh_bbox(v, f, "voxelize")
    longest = float(ext.max())
    if not longest > 0:
        return v  # voxel_grid refuses it
    shift = local_shift(lo, hi, math.frexp(longest)[1])
    if not shift.any():
        return v
    used = np.unique(f)
    out = v.copy()
    out[used] -= shift
    return out


def check_placement(lo: np.ndarray, hi: np.ndarray, pitch: float, what: str) -> None:
    """Refuse a grid whose voxels are finer than the float64 spacing of the
    coordinates they lie among: there no voxel corner or centre can be said
    in the mesh's coordinates (the origin written out would be off by more
    than half a voxel), and the file's coordinates themselves are rounded
    to more than a voxel.

    Parameters
    ----------
    lo, hi : ndarray (3,)
        The mesh's bounding box.
    pitch : float
        The voxel size.
    what : str
        The grid, as :func:`voxel_grid` names it (``"resolution=R"``).

    Raises
    ------
    IsoflowError
        Naming the pitch, the spacing, where the coordinates lie, the
        finest grid that can be placed there and the way out of moving the
        mesh nearer the origin.

    Examples
    --------
    >>> check_placement(np.array([1e15] * 3), np.array([1e15 + 4] * 3), 0.125, "resolution=32")
    >>> check_placement(np.array([1e16] * 3), np.array([1e16 + 4] * 3), 0.125, "resolution=32")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: voxelize: resolution=32 makes voxels of 0.125, finer than the float64
    spacing 2.0 of the coordinates near 1e+16: the grid cannot be placed there; at most resolution=2 can be,
    or move the mesh nearer the origin
    """
    longest = float((hi - lo).max())
    if not longest / pitch < 2.0**52:
        return  # finer than the spacing at the mesh's own size: refused as too large to hold
    far = np.maximum(np.abs(lo), np.abs(hi))
    flat = hi == lo  # one layer of voxels, centred on the plane: nothing to place finer
    spacing = np.where(flat, 0.0, np.spacing(far))
    if not pitch < float(spacing.max()):
        return
    a = int(np.argmax(spacing))
    gap, near = float(spacing[a]), float(far[a])
    finest = math.floor(longest / gap)

    def words(said: Callable[[str], str]) -> str:
        if not what.startswith("resolution="):
            fit = f"{said(f'pitch={gap!r}')} or coarser can be"
        else:
            fit = f"at most {said(f'resolution={finest}')} can be" if finest >= 1 else "no resolution can be"
        return (f"voxelize: {said(what)} makes voxels of {pitch:.6g}, finer than the float64 spacing {gap!r} of the "
                f"coordinates near {near:.6g}: the grid cannot be placed there; {fit}, or move the mesh nearer "
                "the origin")

    raise IsoflowError.worded(words(lambda text: text), words(option_words))


def grid_need(shape, bytes_per_voxel: float, extra: int = 0) -> int:
    """Bytes of a grid of ``shape`` at ``bytes_per_voxel`` and ``extra``
    bytes of temporaries, exactly (Python ints: no overflow however large).

    Examples
    --------
    >>> grid_need((10, 10, 10), 1.125, 7)
    1132
    """
    nvox = math.prod(int(n) for n in shape)
    if nvox < 2**53:
        return int(nvox * bytes_per_voxel) + int(extra)
    from fractions import Fraction

    return int(nvox * Fraction(bytes_per_voxel)) + int(extra)


def grid_fits(shape, bytes_per_voxel: float, extra: int, budget: int) -> bool:
    """Whether a grid of ``shape`` fits in ``budget`` bytes (see
    :func:`grid_need`) and in one array (fewer than 2**62 voxels)."""
    return math.prod(int(n) for n in shape) < 2**62 and grid_need(shape, bytes_per_voxel, extra) <= budget


def grid_words(shape, need: int | None = None) -> str:
    """A grid as its refusal names it: its sides, its voxels and the bytes
    it needs.

    Examples
    --------
    >>> grid_words((2000, 300, 2000), 1_200_000_000)
    'a 2000x300x2000 grid (1,200,000,000 voxels, about 1,200,000,000 bytes)'
    """
    dims = "x".join(fmt_count(n, sep=False) for n in shape)
    nvox = math.prod(int(n) for n in shape)
    return f"a {dims} grid ({fmt_count(nvox)} voxels" + (f", about {fmt_count(need)} bytes)" if need is not None else ")")


def check_grid_memory(shape, what, bytes_per_voxel: float, extra: int, max_bytes,
                      hints: tuple[str, str] = ("", "")) -> None:
    """Refuse (:class:`GridTooLarge`) a grid whose volume (``bytes_per_voxel``
    per voxel) and ``extra`` bytes of temporaries exceed ``max_bytes``
    (default: the memory budget), naming its size; ``hints`` say what to do
    instead, in the Python API's words and the command line's."""
    budget = memory.budget_of(max_bytes)
    if not grid_fits(shape, bytes_per_voxel, extra, budget):
        need = grid_need(shape, bytes_per_voxel, extra)
        raise GridTooLarge(what, grid_words(shape, need), budget, shape=tuple(shape),
                           beyond="" if need > budget else "more than one array can index", hints=hints)


def _bytes(n: int) -> str:
    """A number of bytes as a person reads it, however large."""
    return sized(n) if n < 2**70 else f"{fmt_count(n)} bytes"


def option_words(what: str) -> str:
    """A grid parameter as the command line writes it.

    Examples
    --------
    >>> option_words("resolution=1290"), option_words("pitch=1e-300")
    ('--resolution 1290', '--pitch 1e-300')
    """
    name, _, value = what.partition("=")
    return f"--{name.replace('_', '-')} {value}"


class GridTooLarge(IsoflowError):
    """A voxel grid refused before anything grid-sized is allocated: it
    would not fit in the memory budget, in one array or in a zarr store.

    Its message names the grid asked for, what it needs, the limit and the
    finest grid that fits; :attr:`command_line` says the same with the
    command line's options (``--resolution 1290``) where the message names
    the Python parameters (``resolution=1290``, ``max_bytes``).

    Parameters
    ----------
    what : str
        The grid asked for, as :func:`voxel_grid` names it:
        ``"resolution=R"`` or ``"pitch=P"``.
    needs : str
        What it needs, in words (:func:`grid_words`).
    budget : int
        The bytes it had.
    shape : tuple of int, optional
        Its shape.
    beyond : str
        The limit in words where it is not the budget (one array, a store's
        columns).
    fit : int, float or None
        The finest grid that passes the same checks under the same budget
        (:func:`finest_fit`): the largest resolution, or the smallest pitch
        of three significant digits; None where none does.
    sought : bool
        Whether ``fit`` was looked for (not where the grid was given
        whole, ``grid=`` or ``window=``).
    hints : (str, str)
        What else to do, in the Python API's words and the command line's.
    store : bool
        Whether a zarr store, written slab by slab, would hold the grid
        asked within the same budget.
    place : str
        What the message starts with (the file, the step).
    parameter : str or None
        The Python parameter that set ``budget`` (``max_bytes``); None
        where the caller has none (the memory available, as on the
        command line).
    caller : str or None
        The Python function called, which the message names in the
        command's place (:meth:`called`); None: the command's words.
    """

    def __init__(self, what: str, needs: str, budget: int, *, shape: tuple | None = None, beyond: str = "",
                 fit: int | float | None = None, sought: bool = False, hints: tuple[str, str] = ("", ""),
                 store: bool = False, place: str = "voxelize: ", parameter: str | None = "max_bytes",
                 caller: str | None = None):
        self.facts = {"what": what, "needs": needs, "budget": budget, "shape": shape, "beyond": beyond, "fit": fit,
                      "sought": sought, "hints": tuple(hints), "store": store, "place": place, "parameter": parameter,
                      "caller": caller}
        self.what, self.shape, self.budget, self.fit, self.store = what, shape, budget, fit, store
        super().__init__(self.words(command_line=False))

    def __reduce__(self):  # pickled (a dask worker's error) by its facts, not its message
        return (_grid_too_large, (self.facts,))

    @property  # type: ignore[override]
    def command_line(self) -> str:
        """The message with the command line's options."""
        return self.words(command_line=True)

    def words(self, command_line: bool) -> str:
        """The message in the Python API's words, or the command line's."""
        facts = self.facts
        said = option_words if command_line else (lambda text: text)
        budget = facts["budget"]
        if facts["beyond"]:
            limit = facts["beyond"]
        elif command_line or not facts["parameter"]:  # no option sets it: it is what the system has free
            limit = f"more than the memory budget of {_bytes(budget)} (the memory available now)"
        else:
            limit = f"more than {facts['parameter']}={fmt_count(budget)}"
        place = facts["place"] if command_line or not facts["caller"] else called_words(
            facts["place"], facts["caller"], "voxelize")
        text = f"{place}{said(facts['what'])} needs {facts['needs']}, {limit}"
        room = f" in {_bytes(budget)}" if command_line else ""
        fit = facts["fit"]
        if fit is not None and facts["what"].startswith("pitch="):
            text += f"; {said(f'pitch={fit!r}')} or coarser fits{room}"
        elif fit is not None:
            text += f"; at most {said(f'resolution={fit}')} fits{room}"
        elif facts["sought"]:
            text += f"; not even {said('resolution=1')} fits{room}"
        hint = facts["hints"][1 if command_line else 0]
        return text + (f"; {hint}" if hint else "")

    def at(self, where: object) -> GridTooLarge:
        """This refusal with ``where`` (a file, a mesh) put before it."""
        return self.but(place=f"{where}: {self.facts['place']}")

    def called(self, function: str, command: str | None = None) -> GridTooLarge:
        """This refusal as the Python API's ``function`` raises it: named
        in the command's place, the command line's words as they were."""
        return self.but(caller=function)

    def but(self, **facts) -> GridTooLarge:
        """This refusal with some of its facts changed (``hints=``,
        ``store=``: what the caller knows to do instead)."""
        return GridTooLarge(**{**self.facts, **facts})


def _grid_too_large(facts: dict) -> GridTooLarge:
    return GridTooLarge(**facts)


def box_corners(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two corners of the mesh's bounding box as a mesh whose one face
    uses both: :func:`voxel_grid` lays on it the grid it lays on the mesh
    (it depends on the box alone), at no cost per triangle."""
    lo, hi, _ = mesh_bbox(v, f, "voxelize")
    return np.array([lo, hi]), np.array([[0, 1, 1]])


def coarser_pitch(pitch: float) -> float:
    """``pitch`` rounded up to three significant digits: a pitch a person
    types, no finer than ``pitch``.

    Examples
    --------
    >>> coarser_pitch(0.0038757), coarser_pitch(2.5)
    (0.00388, 2.5)
    """
    from decimal import ROUND_CEILING, Decimal

    d = Decimal(pitch)
    return float(d.quantize(Decimal(1).scaleb(d.adjusted() - 2), rounding=ROUND_CEILING))


def finest_fit(v: np.ndarray, f: np.ndarray, what: str, shape, fits: Callable[[tuple, tuple], bool]) -> int | float | None:
    """The finest grid of the mesh ``(v, f)`` that passes the checks that
    refused the grid ``what`` of ``shape``.

    Parameters
    ----------
    v, f
        The mesh (only its bounding box lays the grids).
    what : str
        The grid refused, as :func:`voxel_grid` names it: ``"resolution=R"``
        or ``"pitch=P"``.
    shape
        Its shape.
    fits : callable
        ``fits(shape, frame)``: whether the grid of ``shape`` in the scaled
        ``frame`` of :func:`voxel_grid` passes the checks (taken as
        monotone: a coarser grid of the same mesh needs no more).

    Returns
    -------
    int, float or None
        For a resolution: the largest one below ``max(shape)`` that fits;
        for a pitch: the smallest pitch of three significant digits that
        fits (about the longest side over that resolution); None where not
        even one voxel along the longest side fits.
    """
    corners, used = box_corners(v, f)

    def fitting(pitch, resolution) -> bool:
        _, _, grid, _, frame = voxel_grid(corners, used, pitch, resolution)
        return fits(grid, frame)

    # bisection: lo fits (0: nothing does), hi does not (the grid refused,
    # or one beyond any resolution)
    lo, hi = 0, min(max(int(n) for n in shape), MAX_RESOLUTION + 1)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fitting(None, mid) else (lo, mid)
    if lo == 0 or not what.startswith("pitch="):
        return lo or None
    # a pitch that a person types: rounded up, it lays a grid no larger on
    # any axis; checked all the same (the slab temporaries are the plan's)
    longest = float((corners[1] - corners[0]).max())
    while lo > 0:
        pitch = coarser_pitch(longest / lo)
        if fitting(pitch, None):
            return pitch
        lo -= max(1, lo // 100)
    return None


#: the float64 spacing at the mesh's largest coordinate, as a share of its
#: median edge, from which :func:`float64_rounding` says the coordinates
#: are held coarsely: a hundredth of an edge already bends faces by a
#: percent of their size, where rounding makes crossings and welds
ROUNDING_SHARE = 0.01


def float64_rounding(v: np.ndarray, f: np.ndarray) -> dict | None:
    """Whether float64 holds the mesh's coordinates coarsely against its
    edges: the spacing of float64 (of float32 where every coordinate is
    one, :func:`stored_precision`: the file stored them so) at the largest
    coordinate magnitude of the vertices the faces use (``np.spacing``) at
    least
    :data:`ROUNDING_SHARE` of the median length of the mesh's distinct
    edges. A mesh saved far from the origin is already rounded onto that
    grid in its file: crossings, welded vertices and non-manifold edges
    that the surface itself does not have.

    Parameters
    ----------
    v : ndarray, shape (N, 3)
        Vertex positions, float64.
    f : ndarray, shape (M, 3)
        Faces, indices into ``v`` (as :func:`~isoflow.mesh.load.check_mesh`
        returns them).

    Returns
    -------
    dict or None
        ``near``: the largest coordinate magnitude; ``spacing``: float64's
        spacing there; ``median_edge``: the median length of the distinct
        edges (each pair of corners once, as trimesh's
        ``edges_unique_length``); ``share``: ``spacing / median_edge``;
        ``precision``: ``"float32"`` or ``"float64"``.
        None where the spacing is below :data:`ROUNDING_SHARE` of the
        median edge.

    Examples
    --------
    >>> v = np.array([[1e15, 0, 0], [1e15 + 1, 0, 0], [1e15, 1, 0]])
    >>> r = float64_rounding(v, np.array([[0, 1, 2]]))
    >>> r["spacing"], r["median_edge"], r["share"]
    (0.125, 1.0, 0.125)
    >>> float64_rounding(v - [1e15, 0, 0], np.array([[0, 1, 2]])) is None
    True
    """
    if not len(f):
        return None
    lo, hi, _ = mesh_bbox(v, f, "mesh")
    near = float(np.maximum(np.abs(lo), np.abs(hi)).max())
    # every face's edges 01, then 12, then 20; the rows gathered by np.take
    # and the squares summed a column at a time, in np.linalg.norm's order
    # (NumPy's fancy index and its sum along a short last axis take slower,
    # general loops)
    a, b = f.T.reshape(-1), f[:, [1, 2, 0]].T.reshape(-1)
    with np.errstate(over="ignore", invalid="ignore"):
        d = np.take(v, a, axis=0) - np.take(v, b, axis=0)
        d *= d
        lengths = np.sqrt(d[:, 0] + d[:, 1] + d[:, 2])
        wide = float(np.spacing(np.float32(near)))
    # the median of the distinct edges is above the bound where no edge is
    # below it: most meshes, near the origin, stop here, before the
    # precision the file stored (a look at every coordinate) is asked; the
    # larger of the two spacings bounds either (float32's is NaN past its
    # range, where no coordinate is a float32)
    widest = max(float(np.spacing(near)), wide if math.isfinite(wide) else 0.0)
    if not np.any(lengths <= widest / ROUNDING_SHARE):
        return None
    precision = stored_precision(v, f)
    spacing = float(np.spacing(np.float32(near) if precision == "float32" else near))
    if not spacing > 0:
        return None
    bound = spacing / ROUNDING_SHARE
    if not np.any(lengths <= bound):
        return None
    pairs = np.sort(np.stack([a, b], axis=1), axis=1)
    _, first = np.unique(pairs, axis=0, return_index=True)
    median = float(np.median(lengths[first]))
    if not (median > 0 and spacing >= ROUNDING_SHARE * median):
        return None
    return {"near": near, "spacing": spacing, "median_edge": median, "share": spacing / median, "precision": precision}


def stored_precision(v: np.ndarray, f: np.ndarray) -> str:
    """``"float32"`` where every coordinate of the vertices the faces use
    is a float32 (as an STL, or a PLY of ``float`` properties, stores
    them), else ``"float64"``: the grid a file far from the origin was
    rounded onto when it was written.

    Examples
    --------
    >>> stored_precision(np.array([[2e6, 0.25, 1.5]]), np.array([[0, 0, 0]]))
    'float32'
    >>> stored_precision(np.array([[2e6 + 0.1, 0.25, 1.5]]), np.array([[0, 0, 0]]))
    'float64'
    """
    used = used_vertices(v, f)
    with np.errstate(over="ignore", invalid="ignore"):
        held = used.astype(np.float32).astype(np.float64) == used
    return "float32" if len(used) and bool(held.all()) else "float64"


def share_words(share: float) -> str:
    """A share of a length in words, for :func:`rounding_words`: a percent
    to the digits a reader compares (two below 10 %), and a multiple past
    a million percent, whose digits in percent would only count zeros.

    Parameters
    ----------
    share : float
        The ratio of two lengths (1.0: equal).

    Returns
    -------
    str
        ``"N % of"`` or ``"N times"``, followed by what it is a share of.

    Examples
    --------
    >>> share_words(0.0123), share_words(0.773), share_words(64.0), share_words(1.1641532182693481e20)
    ('1.2 % of', '77 % of', '6400 % of', '1.16e+20 times')
    """
    pct = 100 * share
    if pct >= 1e6:
        return f"{share:.3g} times"
    return f"{pct:.0f} % of" if pct >= 10 else f"{pct:.2g} % of"


def rounding_words(near: float, spacing: float, median_edge: float, share: float, defects: tuple = (),
                   where: str = "", precision: str = "float64") -> str:
    """:func:`float64_rounding`'s facts in words: the spacing, its share of
    the median edge, the ``defects`` (words naming what was found, such as
    ``"crossings"``) it may have made, said ``where`` (``" above"``), and
    the way out.

    Examples
    --------
    >>> print(rounding_words(1e15, 0.125, 0.1618, 0.125 / 0.1618, ("crossings", "welds"), " above"))
    coordinates near 1e+15 are held by float64 to 0.125, 77 % of the median edge (0.162): the crossings and
    welds above may be that rounding; move the mesh nearer the origin (subtract its centre) before saving it
    """
    # every coordinate a float32: the file stored them so (an STL, a PLY of float properties), and
    # float64 storage is a second way out
    held = "float32 (every coordinate is one, as the file stores them)" if precision == "float32" else "float64"
    said = (f"coordinates near {near:.6g} are held by {held} to {spacing:.6g}, "
            f"{share_words(share)} the median edge ({median_edge:.3g})")
    if defects:
        listed = ", ".join(defects[:-1]) + " and " + defects[-1] if len(defects) > 1 else defects[0]
        said += f": the {listed}{where} may be that rounding"
    return said + ("; move the mesh nearer the origin (subtract its centre)"
                   + (", or store float64 coordinates," if precision == "float32" else "") + " before saving it")
