"""The one exception type isoflow raises for bad input.

The CLI turns it into a one-line message (in its ``command_line`` words where
an error has them) and exit code 2; the Python API lets it propagate. Its
message always names the thing that is wrong (file, field, value) so that
nobody has to read a traceback from inside numpy.
"""

from __future__ import annotations

import contextlib
import copy
import math
import os
import re
import sys
import unicodedata
import warnings
from collections.abc import Iterable
from pathlib import PurePath
from types import FrameType

#: what every reader says of an input that is not there (a volume, a mesh,
#: a zarr store: a directory), after its path
MISSING = "no such file or directory"

#: a URL's scheme, as ``Path`` leaves it (``s3://b/x`` becomes ``s3:/b/x``);
#: two letters at least, so that ``C:/data`` stays a path
_URL = re.compile(r"^(?P<scheme>[A-Za-z][A-Za-z0-9+.-]+):/+(?P<rest>.*)$")


def missing(path: object) -> IsoflowError:
    """The error for an input that is not there: :data:`MISSING` after its
    path, or, for a URL (an ``s3://`` bucket, an ``https://`` file), that
    isoflow reads local paths only (there is no file of that name, and
    "no such file" would send the user looking for a typo).

    Parameters
    ----------
    path : str or os.PathLike
        The input as given, or as ``pathlib.Path`` made it.

    Returns
    -------
    IsoflowError
        The one-line error to raise: a :class:`NoSuchFile` (also a
        ``FileNotFoundError``) for a local path.

    Examples
    --------
    >>> str(missing("scan.npy")), isinstance(missing("scan.npy"), FileNotFoundError)
    ('scan.npy: no such file or directory', True)
    >>> str(missing("s3:/bucket/scan.zarr"))  # doctest: +ELLIPSIS
    's3://bucket/scan.zarr: a URL; isoflow reads local files and directories: ...'
    """
    m = _URL.match(str(path))
    if m is None:
        return NoSuchFile(f"{path}: {MISSING}")
    return IsoflowError(f"{m['scheme']}://{m['rest']}: a URL; isoflow reads local files and directories: "
                        "download it, or mount the bucket (s3fs, gcsfuse, rclone mount) and give the path")


def counted(n: int, one: str, many: str | None = None) -> str:
    """A count and its noun in a message, the noun singular for 1 (``many``:
    a plural other than ``one`` + "s").

    Examples
    --------
    >>> counted(1, "cavity", "cavities"), counted(3, "cavity", "cavities"), counted(0, "label")
    ('1 cavity', '3 cavities', '0 labels')
    """
    return f"{n} {one if n == 1 else many or one + 's'}"


def some_of(items: Iterable[object], shown: int = 3, sep: str = ", ", noun: str = "") -> str:
    """The first ``shown`` of ``items`` in a message, and how many more
    there are: the one wording of every list a message cuts short (a run's
    hundreds of step files, an image's thousands of labels).

    The count follows the items behind ``sep`` and "and" where two or more
    are shown (``"a, b, c, and 4 more"``): an item may hold an "and" of its
    own (``"1 and 2: 5"``, a pair of labels) or be a clause (``sep="; "``),
    which a bare "and" would run into the count.

    Parameters
    ----------
    items : iterable
        What the message lists, in the order it names them; each as
        ``str`` prints it.
    shown : int, optional
        How many are named (at least 1); 3 by default.
    sep : str, optional
        What separates them; ``", "`` by default.
    noun : str, optional
        What an item is (singular), said after the count: ``"pair"`` gives
        ``"and 1 more pair"``, ``"and 4 more pairs"``; nothing by default.

    Returns
    -------
    str
        The items joined by ``sep``, all of them where there are no more
        than ``shown``.

    Examples
    --------
    >>> some_of(["a", "b", "c", "d", "e"]), some_of(["a", "b"]), some_of([])
    ('a, b, c, and 2 more', 'a, b', '')
    >>> some_of(["step_000.zarr", "step_001.zarr"], shown=1), some_of(range(12), shown=2, noun="label")
    ('step_000.zarr and 1 more', '0, 1, and 10 more labels')
    >>> some_of(["x is 0.5", "y is -1", "z is 2"], shown=2, sep="; ")
    'x is 0.5; y is -1; and 1 more'
    """
    words = [str(item) for item in items]
    shown = max(1, shown)
    if len(words) <= shown:
        return sep.join(words)
    rest = len(words) - shown
    count = counted(rest, f"more {noun}") if noun else f"{rest} more"
    return sep.join(words[:shown]) + (sep if shown > 1 else " ") + "and " + count


def with_article(word: object) -> str:
    """A word in a message behind its indefinite article: ``an`` before
    a vowel (a NumPy type ``int16``, ``int64``, ``object``), ``a``
    otherwise (``uint8``, ``float32``, ``bool``); a message of a
    ``f"a {dtype} array"`` read "a int16".

    Parameters
    ----------
    word : object
        The word, or what prints as it (a NumPy dtype, a type's name).

    Returns
    -------
    str
        The article, a space and the word as ``str`` prints it.

    Examples
    --------
    >>> with_article("int32"), with_article("uint8"), with_article("float32"), with_article("OrderedDict")
    ('an int32', 'a uint8', 'a float32', 'an OrderedDict')
    """
    text = str(word)
    # a "u" starts uint8 and unicode with the sound of "you": a, as it is said
    return f"{'an' if text[:1].lower() in ('a', 'e', 'i', 'o') else 'a'} {text}"


def number_text(value: object) -> str:
    """A number in a message as the user wrote or meant it: a whole number
    in all its digits (``-1``, not the ``-1.0`` its conversion to float
    prints; ``%g`` made 2**40 + 1 and 2**40 alike), any other float in its
    shortest repr (``0.5``, ``1e-07``, and a whole float past 2**53,
    ``1e+300``), a sequence as a list of them, and anything else (a
    string, None) as its repr. An int is whole digit by digit, however
    large (``18446744073709551617``).

    Parameters
    ----------
    value : object
        The value given: a Python or NumPy number, an array or a sequence.

    Returns
    -------
    str

    Examples
    --------
    >>> import numpy as np
    >>> number_text(-1.0), number_text(np.float32(0.5)), number_text(1e-07), number_text(True)
    ('-1', '0.5', '1e-07', '1')
    >>> number_text((1.5, 0.0)), number_text(np.array([2**40 + 1])), number_text(np.float32(0.1)), number_text("x")
    ('[1.5, 0]', '[1099511627777]', '0.1', "'x'")
    >>> number_text(1e300), number_text(18446744073709551617)
    ('1e+300', '18446744073709551617')
    """
    if getattr(value, "shape", None):  # a NumPy array: its elements (or rows) are NumPy's scalars
        return "[" + ", ".join(number_text(v) for v in value) + "]"  # type: ignore[attr-defined]
    value = _python_scalar(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(number_text(v) for v in value) + "]"
    if isinstance(value, bool):  # a mask's values: 0 and 1
        value = int(value)
    if isinstance(value, float) and value.is_integer() and abs(value) < 2.0**53:
        # past 2**53 a float is no whole number the user wrote digit by digit: 1e300 in all its digits is
        # 301 of them, the last 285 the float's rounding; its shortest repr is what the user meant
        value = int(value)
    if isinstance(value, float):
        return repr(value)
    return str(value) if isinstance(value, int) else repr(value)


def given_text(value: object) -> str:
    """A value given to a function, as a message says it: its repr, a NumPy
    scalar's as the Python value it holds (NumPy 2's repr names the type,
    ``np.int64(0)``, where the user wrote or took the number ``0``), a list
    or tuple element by element.

    Parameters
    ----------
    value : object
        The value given.

    Returns
    -------
    str

    Examples
    --------
    >>> import numpy as np
    >>> given_text(np.int64(0)), given_text(np.True_), given_text(np.float32(0.1)), given_text(1.0), given_text("x")
    ('0', 'True', '0.1', '1.0', "'x'")
    >>> given_text((np.int64(3), 0.5)), given_text([np.uint8(7)]), given_text((np.int64(2),))
    ('(3, 0.5)', '[7]', '(2,)')
    >>> given_text(np.zeros((3, 3)))  # an array's repr runs over lines: its type and shape
    'ndarray of shape (3, 3)'
    >>> given_text(np.array([6, 26]))  # a few numbers, as a list
    '[6, 26]'
    """
    if isinstance(getattr(value, "shape", None), tuple) and value.shape != () and hasattr(value, "dtype"):  # type: ignore[attr-defined]
        if value.ndim == 1 and 0 < value.size <= 8 and value.dtype.kind in "biuf":  # type: ignore[attr-defined]
            return given_text(value.tolist())  # type: ignore[attr-defined]
        return value_kind(value)
    if type(value) in (list, tuple):
        inner = ", ".join(given_text(v) for v in value)  # type: ignore[attr-defined]
        return f"[{inner}]" if isinstance(value, list) else f"({inner},)" if len(value) == 1 else f"({inner})"  # type: ignore[arg-type]
    return repr(_python_scalar(value))


def scalar_given(value: object) -> object:
    """A 0D array given for a number as the NumPy scalar it holds; anything
    else as it is.

    ``np.load`` of a number saved with ``np.savez``, an HDF5 scalar dataset
    and ``np.asarray(6)`` give a 0D array, which NumPy's own indexing takes
    as the integer it holds. The checks of integer arguments take the
    scalar: given the array, they refused ``array(6)`` as "connectivity 6
    ... must be an integer", a line that contradicts itself.

    Parameters
    ----------
    value : object
        What the caller passed.

    Returns
    -------
    object
        ``value[()]`` for a 0D array (a NumPy scalar, which
        :func:`whole_given` takes or refuses as it does the scalar),
        ``value`` for anything else.

    Examples
    --------
    >>> import numpy as np
    >>> scalar_given(np.array(6)), scalar_given(6), scalar_given([6]), scalar_given(np.str_("6"))
    (np.int64(6), 6, [6], np.str_('6'))
    """
    # a NumPy string (np.str_("6")) has a shape and a dtype too, but its
    # indexing is str's, which takes no tuple: it is refused as the text it is
    if getattr(value, "shape", None) == () and hasattr(value, "dtype") and hasattr(value, "__getitem__") \
            and not isinstance(value, (str, bytes)):
        return value[()]
    return value


def whole_given(value: object) -> int | None:
    """The integer an integer argument of the public API gives, or None
    where it gives none: the one rule that every such argument follows
    (``connectivity``, ``resolution``, ``steps``, ``threads``, ``time``,
    labels asked for, ...).

    A whole number is taken as a Python ``int``, a NumPy integer, or a
    float (Python's or NumPy's) that is whole: ``6.0`` is 6, as arithmetic
    (``n / 2 * 2``, a ``float64`` column) gives it. A bool is none, though
    ``True`` equals 1, nor is a float with a fraction (``6.5``), NaN, an
    infinity, a string, a ``Fraction`` or a ``Decimal``. A 0D array is the
    scalar it holds (:func:`scalar_given`). The caller says which range it
    takes and names the argument and its value where this gives None.

    Parameters
    ----------
    value : object
        An integer argument, as given.

    Returns
    -------
    int or None
        The Python integer, or None where ``value`` is no whole number.

    Examples
    --------
    >>> import numpy as np
    >>> whole_given(6), whole_given(np.int64(6)), whole_given(6.0), whole_given(np.array(26.0))
    (6, 6, 6, 26)
    >>> whole_given(6.5), whole_given(True), whole_given(float("nan")), whole_given("6")
    (None, None, None, None)
    """
    value = scalar_given(value)
    # NumPy's scalars by their dtype: errors.py is imported before NumPy is needed
    kind = getattr(getattr(value, "dtype", None), "kind", None) if getattr(value, "shape", None) == () else None
    if isinstance(value, bool) or kind == "b":
        return None
    if isinstance(value, int) or kind in ("i", "u"):
        return int(value)  # type: ignore[call-overload]  # an integer, as just checked
    if isinstance(value, float) or kind == "f":
        number = float(value)  # type: ignore[arg-type]  # a float, as just checked
        return int(number) if math.isfinite(number) and number.is_integer() else None
    return None


def _python_scalar(value: object) -> object:
    """A NumPy scalar (or 0D array) as the Python value it holds; anything
    else as it is."""
    if getattr(value, "shape", None) == () and hasattr(value, "dtype"):
        # NumPy's str of a float32 is its shortest (0.1), which item() widens to 0.10000000149011612
        return float(str(value)) if value.dtype.kind == "f" else value.item()  # type: ignore[attr-defined]
    return value


def path_text(path: str | os.PathLike) -> str:
    """A path as text that every reader of UTF-8 takes: a byte of the name
    that the file system's encoding does not decode is written ``\\xNN``.
    Python holds such a byte as a lone surrogate (PEP 383), which
    ``json.dumps`` writes as ``\\udcNN``: not a character, so that strict
    JSON parsers (Perl's JSON::PP) refuse the line and others (jq) read
    U+FFFD in its place.

    Parameters
    ----------
    path : str or os.PathLike
        The path as the command line or the caller gave it.

    Returns
    -------
    str
        The path, unchanged where it decodes.

    Examples
    --------
    >>> path_text("scan.nii.gz"), path_text(os.fsdecode(b"caf\\xe9.npy"))
    ('scan.nii.gz', 'caf\\\\xe9.npy')
    """
    text = os.fsdecode(path)
    try:
        return os.fsencode(text).decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate that no file system byte gave (written in the string itself)
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def line_text(text: str) -> str:
    r"""A name read from a file (a label's, a segment's) as a terminal
    line shows it: each control character (a tab, a line break, an
    escape that a terminal would act on) as Python writes it escaped,
    ``\t``, ``\x1b``; any other character as it is.

    Parameters
    ----------
    text : str
        The name.

    Returns
    -------
    str
        One line of printable text.

    Examples
    --------
    >>> line_text("tab\there"), line_text("\x1b[31mred"), line_text("Leber \u00f8") == "Leber \u00f8"
    ('tab\\there', '\\x1b[31mred', True)
    """
    if text.isprintable():
        return text
    return "".join(c.encode("unicode_escape").decode("ascii") if unicodedata.category(c) == "Cc" else c
                   for c in text)


def terminal_text(text: str | os.PathLike) -> str:
    r"""A line that names files (a report's, a message's), or a file's name
    alone, as a terminal shows it: a byte of a name that is not UTF-8 as
    ``\xNN`` (:func:`path_text`), and each control character escaped
    (:func:`line_text`), so that a name holding a line break or an escape
    sequence neither splits the line nor acts on the terminal. JSON keeps
    the name as it is.

    Parameters
    ----------
    text : str or os.PathLike
        A whole line of a report or message (each is one line), or a path.

    Returns
    -------
    str
        ``text`` as valid UTF-8 with no control character in it.

    Examples
    --------
    >>> terminal_text("\x1b[2Jscan.npy: 64 voxels"), terminal_text(os.fsdecode(b"a\tb\xe9.npy"))
    ('\\x1b[2Jscan.npy: 64 voxels', 'a\\tb\\xe9.npy')
    """
    return line_text(path_text(text))


#: the nouns of the Betti numbers b0, b1, ... of a volume of each dimension
#: (singular, plural); a 4-D volume's b1 and b2 have no everyday name
_BETTI_NOUNS = {
    2: (("component", "components"), ("hole", "holes")),
    3: (("component", "components"), ("tunnel", "tunnels"), ("cavity", "cavities")),
    4: (("component", "components"), ("b1", "b1"), ("b2", "b2"), ("enclosed background", "enclosed background")),
}


def betti_words(betti) -> str:
    """The Betti numbers of a 2-, 3- or 4-D volume as a message says them,
    each noun singular for 1 (an unknown number is ``?``).

    Parameters
    ----------
    betti : sequence of int or None
        b0, b1, ... (two, three or four of them).

    Returns
    -------
    str
        The counts and their nouns, comma-separated.

    Examples
    --------
    >>> betti_words([1, 2, 0])
    '1 component, 2 tunnels, 0 cavities'
    >>> betti_words([2, 1]), betti_words([1, None, 1])
    ('2 components, 1 hole', '1 component, ? tunnels, 1 cavity')
    """
    return ", ".join(f"? {many}" if b is None else counted(b, one, many)
                     for b, (one, many) in zip(betti, _BETTI_NOUNS[len(betti)]))


def coordinates(values, digits: int = 6, step=None) -> str:
    """A point (an origin, a corner) in a message, each coordinate to
    ``digits`` significant digits: rounding to decimal places would print
    the origin of a model in micrometres as 0 or -1e-06; with ``step`` (a
    voxel size: one number, or one per coordinate) to as many more as keep
    it within a 200th of a step, so that the origin of a model near 1e6 in
    voxels of 0.04 is not printed seven voxels away, as 1e+06. With
    ``step``, a coordinate within a billionth of a step of 0 is 0: that is
    float64's rounding of ``origin + pitch * lattice`` (the centre of
    voxels symmetric about 0 comes out as ``1.11022e-16``), not a place.

    Parameters
    ----------
    values : sequence of float
        The coordinates.
    digits : int
        Significant digits of each, at least.
    step : float or sequence of float, optional
        The finest difference that must show, per coordinate.

    Returns
    -------
    str
        ``[x, y, z]``.

    Examples
    --------
    >>> coordinates([-1.3e-06, -3.25e-07, -0.2734375]), coordinates([1.0, 2.0, 3.0])
    ('[-1.3e-06, -3.25e-07, -0.273438]', '[1, 2, 3]')
    >>> coordinates([999998.7, 0.0, 999999.6953125]), coordinates([999998.7, 0.0, 999999.6953125], step=0.04)
    ('[999999, 0, 1e+06]', '[999998.7, 0, 999999.69531]')
    >>> coordinates([1.1102230246251565e-16, -0.0002575, -5.551115123125783e-17], step=0.1)
    '[0, -0.0002575, 0]'

    A coordinate that is not known (None: float64 cannot hold it,
    :mod:`isoflow.digital.float64`) is a ``?``:

    >>> coordinates([None, 2.5])
    '[?, 2.5]'
    """
    values = [None if x is None else float(x) for x in values]
    steps = [step] * len(values) if step is None or not hasattr(step, "__len__") else [float(s) for s in step]
    values = [_without_noise(x, s) for x, s in zip(values, steps)]
    return "[" + ", ".join("?" if x is None else f"{x:.{_digits_for(x, s, digits)}g}" for x, s in zip(values, steps)) + "]"


def _without_noise(x: float | None, step) -> float | None:
    """``x``, or 0 where it lies within a billionth of ``step`` of 0 (the
    rounding of a placement's float64 arithmetic, which a place that far
    below a voxel cannot be told from)."""
    if x is None or step is None or not (math.isfinite(step := float(step)) and step > 0):
        return x
    return 0.0 if abs(x) <= step * 1e-9 else x


def _digits_for(x: float, step, digits: int) -> int:
    """Significant digits of ``x`` that keep it within a 200th of ``step``
    (at least ``digits``, at most 17: float64 holds no more)."""
    if step is None or not (math.isfinite(x) and math.isfinite(step := float(step)) and x != 0 and step > 0):
        return digits
    return min(17, max(digits, math.ceil(math.log10(abs(x) / step)) + 3))


def check_callable(value: object, name: str, call: str) -> None:
    """Refuse, before any work, a callback that cannot be called: it failed
    at its first call, after a step or a slab, as ``TypeError: 'int' object
    is not callable``, which names neither the argument nor its value.

    Parameters
    ----------
    value : object
        What the caller passed (None: no callback).
    name : str
        The argument's name.
    call : str
        How it is called, for the message.

    Raises
    ------
    TypeError
        If ``value`` is neither None nor callable.

    Examples
    --------
    >>> check_callable(print, "progress", "progress(done, total)")
    >>> check_callable(5, "progress", "progress(done, total)")
    Traceback (most recent call last):
    ...
    TypeError: progress must be a callable, progress(done, total), or None; got 5
    """
    if value is not None and not callable(value):
        raise TypeError(f"{name} must be a callable, {call}, or None; got {given_text(value)}")


def value_kind(value: object, width: int = 60) -> str:
    """What a value is, in one short line of a message: its type, and its
    shape where it has one (an array's repr runs over many lines), else its
    repr cut to about ``width`` characters.

    Parameters
    ----------
    value : object
        What the caller passed.
    width : int
        The most characters of a repr kept.

    Returns
    -------
    str
        ``TYPE of shape (...)`` or ``TYPE REPR`` (a repr that begins with
        its type's name alone).

    Examples
    --------
    >>> import numpy as np
    >>> value_kind(np.zeros((3, 3, 3), bool)), value_kind(None), value_kind(["a.npy"])
    ('ndarray of shape (3, 3, 3)', 'NoneType None', "list ['a.npy']")
    >>> value_kind(ValueError("a" * 80))
    "ValueError('aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa..."
    """
    name = type(value).__name__
    shape = getattr(value, "shape", None)
    if isinstance(shape, tuple):
        return f"{name} of shape {shape}"
    text = " ".join(repr(value).split())
    text = text if len(text) <= width else text[:width - 3] + "..."
    return text if text.startswith(name + "(") else f"{name} {text}"  # DigitalObject(...) names its type


def voxeliser_of(value: object) -> str:
    """The function that voxelises ``value`` where it is a mesh in memory,
    for a message that refuses it where a file is taken: a triangle mesh (a
    ``trimesh.Trimesh`` or ``Scene``) names ``voxelize_mesh``, a
    ``manifold3d.Manifold`` ``from_manifold``; "" for anything else. A mesh
    is known by its fields, as :func:`isoflow.scale.arrays.refuse_object`
    knows one: this layer cannot import trimesh or manifold3d.

    Parameters
    ----------
    value : object
        Anything given where a file is taken.

    Returns
    -------
    str
        ``a mesh in memory: ...`` or ``a manifold3d.Manifold in memory:
        ...``, or "".

    Examples
    --------
    >>> class Scene:  # a trimesh.Scene's fields
    ...     graph = geometry = to_mesh = None
    >>> voxeliser_of(Scene()), voxeliser_of("torus.obj")
    ('a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)', '')
    """
    if type(value).__name__ == "Manifold" and hasattr(value, "to_mesh"):
        return "a manifold3d.Manifold in memory: isoflow.from_manifold(manifold, pitch=P)"
    scene = all(hasattr(value, name) for name in ("graph", "geometry", "to_mesh"))
    faces = getattr(value, "faces", None)
    if scene or (hasattr(value, "vertices") and getattr(faces, "shape", (0, 0))[1:] == (3,)):
        return "a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)"
    return ""


def check_path(value: object, name: str, where: str, array_hint: str = "", hint: str = "") -> str | os.PathLike:
    """Refuse, before any work, a path that is not a str or os.PathLike (the
    arguments swapped, an array or a mesh where its file is taken, None):
    ``Path()`` and ``open()`` raise a TypeError that names neither the
    argument nor the function, and a message built on ``str(path)`` printed
    a whole array. A path taken is returned as the readers and the messages
    use it: an os.PathLike that is no :class:`pathlib.PurePath` as the str
    it stands for (``os.fspath``), since the ``str()`` of such an object
    need not be its path (an ``os.DirEntry`` of ``os.scandir`` gives a repr).

    Parameters
    ----------
    value : object
        What the caller passed.
    name : str
        The argument's name.
    where : str
        The function, for the message.
    array_hint : str, optional
        What takes an array, said where ``value`` is one (its shape is
        said): a volume in memory given to a reader of files. Where it is
        given, a mesh in memory is refused naming what voxelises it
        (:func:`voxeliser_of`).
    hint : str, optional
        What to do instead, said whatever ``value`` is.

    Returns
    -------
    str or os.PathLike
        ``value``, a str or a :class:`pathlib.PurePath` as given, any other
        os.PathLike as ``os.fsdecode`` gives it.

    Raises
    ------
    NotAPath
        If ``value`` is neither a str nor an os.PathLike: an
        :class:`IsoflowError` and a ``TypeError``.
    IsoflowError
        If it is the empty path, ``""``.

    Examples
    --------
    >>> import numpy as np
    >>> check_path("scan.npy", "path", "read_volume")
    'scan.npy'
    >>> check_path(np.zeros((3, 3, 3), bool), "path", "read_volume", "give the array to DigitalObject")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.NotAPath: read_volume: path must be a str or os.PathLike, got ndarray of shape (3, 3, 3); give the ...
    """
    if not isinstance(value, (str, os.PathLike)):
        if array_hint and isinstance(getattr(value, "shape", None), tuple):
            hint = array_hint
        elif array_hint and voxeliser_of(value):  # a reader of volumes given a mesh, as analyze() names it
            hint = voxeliser_of(value)
        raise NotAPath(f"{where}: {name} must be a str or os.PathLike, got {value_kind(value)}"
                       + (f"; {hint}" if hint else ""))
    refuse_empty_path(value, f"{where}: {name}")
    return value if isinstance(value, (str, PurePath)) else os.fsdecode(value)


def refuse_empty_path(value: str | os.PathLike, named: str) -> None:
    """Refuse the empty path ``""`` (an unset setting), which ``Path``
    reads as the current directory: a reader or a writer then refused a
    directory, naming neither the argument nor what was wrong with it.

    Parameters
    ----------
    value : str or os.PathLike
        The path given.
    named : str
        The argument as the message names it.

    Raises
    ------
    IsoflowError
        If ``value`` is the empty path.

    Examples
    --------
    >>> refuse_empty_path("scan.npy", "read_volume: path")
    >>> refuse_empty_path("", "read_volume: path")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: read_volume: path is '', an empty file name; give the file's name
    """
    if not os.fsdecode(value):
        raise IsoflowError(f"{named} is '', an empty file name; give the file's name")


def called_words(text: str, function: str, command: str | None = None) -> str:
    """A refusal's words as the Python API's ``function`` says them: where
    ``command`` is given, its name (at the start, or after the file or mesh
    the words begin with) in the function's place, and words that do not
    name it as they are; without it, the function's name before words
    that do not begin with it.

    Parameters
    ----------
    text : str
        The refusal's words.
    function : str
        The function called.
    command : str, optional
        The command whose name the words may give.

    Returns
    -------
    str

    Examples
    --------
    >>> called_words("voxelize: no meshes given", "voxelize_meshes", "voxelize")
    'voxelize_meshes: no meshes given'
    >>> called_words("a.stl: voxelize: empty mesh", "voxelize_file", "voxelize")
    'a.stl: voxelize_file: empty mesh'
    >>> called_words("a.stl: no such file or directory", "voxelize_file", "voxelize")
    'a.stl: no such file or directory'
    >>> called_words("'pitch' must be positive, got -1", "analyze"), called_words("analyze: x", "analyze")
    ("analyze: 'pitch' must be positive, got -1", 'analyze: x')
    """
    if command is None:
        return text if text.startswith(f"{function}:") else f"{function}: {text}"
    head = f"{command}: "
    at = 0 if text.startswith(head) else text.find(f": {head}") + 2
    return text if at == 1 else text[:at] + f"{function}: " + text[at + len(head):]


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
    no-such-volume.npy: no such file or directory
    """

    #: the message in the command line's words where they differ from the
    #: Python API's (its options, ``--resolution``, where the message names
    #: a function's parameter, ``resolution=``); None where they are the same
    command_line: str | None = None

    @classmethod
    def worded(cls, python: str, command_line: str) -> IsoflowError:
        """An error whose message names the Python API's parameters
        (``force=True``) and whose :attr:`command_line` the command's options
        (``--force``).

        Examples
        --------
        >>> e = IsoflowError.worded("a.ply: exists; pass force=True to overwrite", "a.ply: exists; pass --force to overwrite")
        >>> str(e), e.command_line
        ('a.ply: exists; pass force=True to overwrite', 'a.ply: exists; pass --force to overwrite')
        """
        out = cls(python)
        out.command_line = command_line
        return out

    def called(self, function: str, command: str | None = None) -> IsoflowError:
        """This error as the Python API's ``function`` raises it, its
        message in :func:`called_words`, its :attr:`command_line` words as
        they were: a refusal a function shares with the command line, or
        with another function, named the command or nothing where the
        caller called the function.

        Parameters
        ----------
        function : str
            The function called.
        command : str, optional
            The command's name, as the shared refusal begins with it.

        Returns
        -------
        IsoflowError
            Of this error's kind (a copy); this error itself where its
            message is left as it is.

        Examples
        --------
        >>> e = IsoflowError("mesh 1: voxelize: no faces").called("voxelize_meshes", "voxelize")
        >>> str(e), e.command_line
        ('mesh 1: voxelize_meshes: no faces', 'mesh 1: voxelize: no faces')
        """
        text = str(self)
        python = called_words(text, function, command)
        if python == text:
            return self
        out = copy.copy(self)  # of its kind, with its attributes (a NotBinary's remedy, a NoSuchFile's errno)
        out.args = (python,)
        out.command_line = text if self.command_line is None else self.command_line
        return out

    def at(self, where: object) -> IsoflowError:
        """This error with ``where`` (a file, a mesh) put before its
        message, in both wordings.

        Parameters
        ----------
        where : object
            What the error is about, as its message names it.

        Returns
        -------
        IsoflowError
            A new error (a subclass keeps its kind: see
            :meth:`isoflow.mesh.grid.GridTooLarge.at`).

        Examples
        --------
        >>> str(IsoflowError(MISSING).at("a.npy"))
        'a.npy: no such file or directory'
        """
        out = IsoflowError(f"{where}: {self}")
        if self.command_line is not None:
            out.command_line = f"{where}: {self.command_line}"
        return out

    def __reduce__(self):
        # pickle's own recipe for an exception (the class called with its
        # args, then its attributes), given as this class's: tblib, which
        # dask.distributed installs on a worker's error, rebuilds an error
        # whose class has a custom __init__ and no __reduce__ through
        # cls.__new__, which NoSuchFile (a ValueError and an OSError)
        # refuses; distributed then sends a plain Exception of its repr
        return type(self), self.args, self.__dict__ or None


class NotAPath(IsoflowError, TypeError):
    """A path argument that is no ``str`` or ``os.PathLike`` (an array, a
    mesh, None): one line as every :class:`IsoflowError`, and a
    ``TypeError``, what ``os.fspath`` raises, so that code catching that
    still does.

    Examples
    --------
    >>> issubclass(NotAPath, IsoflowError), issubclass(NotAPath, TypeError)
    (True, True)
    """


class NoSuchFile(IsoflowError, FileNotFoundError):
    """An input that is not there (:func:`missing`): one line as every
    :class:`IsoflowError`, and a ``FileNotFoundError``, so that code written
    for ``open()``'s error catches it too.

    Examples
    --------
    >>> e = missing("scan.npy")
    >>> type(e).__name__, isinstance(e, FileNotFoundError), isinstance(e, IsoflowError)
    ('NoSuchFile', True, True)
    """


class DoesNotFit(IsoflowError):
    """The refusal of work that would not fit in memory
    (:func:`isoflow.scale.memory.check_fits`): a caller that has another
    way to the same answer in less memory takes that one instead
    (``label_table`` of a noisy label image, label by label).

    Examples
    --------
    >>> from isoflow.scale.memory import check_fits
    >>> try:
    ...     check_fits(2 << 30, "the table", budget=1 << 30)
    ... except DoesNotFit as exc:
    ...     print(isinstance(exc, IsoflowError), str(exc).split(" (")[0])
    True the table needs about 2.0 GiB of memory, more than the budget of 1.0 GiB
    """


class IsoflowWarning(UserWarning):
    """Something a user should know that is not an error: a file format that
    cannot keep the voxel size, an affine's rotation left out. The command
    line prints it as one ``warning:`` line.

    Examples
    --------
    A ``.npy`` file holds the array alone, so writing one says that the
    pitch is lost (once the file is written); a program can make that an
    error, to stop there:

    >>> import tempfile
    >>> import warnings
    >>> import numpy as np
    >>> import isoflow
    >>> obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5)
    >>> path = tempfile.mkdtemp() + "/cube.npy"
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", isoflow.IsoflowWarning)
    ...     isoflow.write_volume(obj, path)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowWarning: .../cube.npy: a .npy holds the array alone; its pitch [0.5, 0.5, 0.5] is not kept ...
    """


#: the files whose frames a warning skips: isoflow's own, and contextlib's
#: (a ``with`` block's exit runs isoflow code from there)
_INSIDE = (os.path.dirname(os.path.abspath(__file__)) + os.sep, os.path.abspath(contextlib.__file__))


def warn(message: str, category: type[Warning] = IsoflowWarning) -> None:
    """Issue a warning attributed to the first caller outside isoflow: the
    user's line, however deep inside isoflow it was raised (a fixed
    ``stacklevel`` points at isoflow's own code where the depth varies).

    Parameters
    ----------
    message : str
        The warning's one line.
    category : type, optional
        A :class:`Warning` subclass; :class:`IsoflowWarning` by default.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn("pitch dropped")
    >>> str(caught[0].message), caught[0].category.__name__, caught[0].filename.endswith("errors.py")
    ('pitch dropped', 'IsoflowWarning', False)
    """
    frame: FrameType | None = sys._getframe(1)
    level = 2
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_INSIDE):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


class MeshNote(IsoflowWarning):
    """What is unusual about a mesh that was voxelised, and the rule that
    read it (double-sided faces, boundary edges, an empty solid and the
    fill that gives the model): the ``note`` of
    :class:`~isoflow.mesh.voxelize.Voxelization`, issued as a warning
    when the caller did not ask for the details. The command line prints it
    as one ``note:`` line."""


def choice_of(value: object, choices: tuple[str, ...]) -> str | None:
    """``value`` as the plain ``str`` of ``choices`` it names (a
    ``np.str_``, or a 0D array of one, too), else None. An array is none
    of them: ``value in choices`` compares it element by element, and
    NumPy refuses the truth of the comparison (a ValueError where the
    caller meant to say which argument is wrong).

    Parameters
    ----------
    value : object
        What was given.
    choices : tuple of str
        The words it may be.

    Returns
    -------
    str or None

    Examples
    --------
    >>> import numpy as np
    >>> choice_of(np.str_("shell"), ("winding", "shell")), choice_of(np.array(["shell"]), ("winding", "shell"))
    ('shell', None)
    """
    if getattr(value, "shape", None) == () and hasattr(value, "dtype"):
        value = value.item()  # type: ignore[attr-defined]
    return str(value) if isinstance(value, str) and value in choices else None


def check_switch(value: object, name: str, where: str) -> bool:
    """``value`` as a bool where it is True or False (NumPy's bools too),
    else IsoflowError naming ``where`` and the argument: a string such as
    "no" is truthy, and would replace a file, change a format or run a
    guarded flow unasked (and a result would hold "no" for a bool).

    Parameters
    ----------
    value : object
        What was given.
    name : str
        The argument's name.
    where : str
        The function or file, for the message.

    Returns
    -------
    bool

    Examples
    --------
    >>> check_switch(False, "force", "s.ply")
    False
    >>> check_switch("no", "force", "s.ply")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: s.ply: force must be True or False, got 'no'
    """
    import numpy as np

    value = scalar_given(value)  # a 0D array of a bool is that bool
    if not isinstance(value, (bool, np.bool_)):
        raise IsoflowError(f"{where}: {name} must be True or False, got {given_text(value)}")
    return bool(value)
