"""Length units: isoflow's one spelling per unit of the voxel size and
origin, read from the formats' many (:func:`length_unit`), and the check of
a unit a user gives (:func:`unit_given`), which a
:class:`~isoflow.digital.lattice.DigitalObject` and the writers share.
"""

from __future__ import annotations

import re

from ..errors import IsoflowError

#: one spelling per length unit, so that reports of files from different
#: tools compare: each spelling isoflow gives, with the names and symbols
#: the formats write for it (NIfTI's xyzt units, NRRD's and ImageJ's free
#: text, OME-XML's symbols, OME-Zarr's UDUNITS names); names are matched
#: in any case, symbols as written (OME-XML's "Mm" is a megametre)
LENGTH_UNITS = {
    "m": ("m", "meter", "metre", "meters", "metres"),
    "cm": ("cm", "centimeter", "centimetre", "centimeters", "centimetres"),
    "mm": ("mm", "millimeter", "millimetre", "millimeters", "millimetres"),
    "\u00b5m": ("\u00b5m", "\u03bcm", "um", "micron", "microns", "micrometer", "micrometre", "micrometers",
                "micrometres"),
    "nm": ("nm", "nanometer", "nanometre", "nanometers", "nanometres"),
    "pm": ("pm", "picometer", "picometre", "picometers", "picometres"),
    "\u00c5": ("\u00c5", "angstrom", "angstroms", "\u00e5ngstr\u00f6m"),
    "km": ("km", "kilometer", "kilometre", "kilometers", "kilometres"),
    "in": ("in", "inch", "inches"),
    "ft": ("ft", "foot", "feet"),
    "yd": ("yd", "yard", "yards"),
    "mi": ("mi", "mile", "miles"),
}
#: picometres per length unit of :data:`LENGTH_UNITS`, each a whole number
#: that float64 holds exactly, so that the ratio of two (1000 from mm to
#: µm) is the float nearest the true one
PICOMETRES = {"m": 1e12, "cm": 1e10, "mm": 1e9, "\u00b5m": 1e6, "nm": 1e3, "pm": 1.0, "\u00c5": 1e2, "km": 1e15,
              "in": 2.54e10, "ft": 3.048e11, "yd": 9.144e11, "mi": 1.609344e15}
#: what the formats write for "no unit": NIfTI's "unknown", ImageJ's
#: "pixel" (an uncalibrated image), NRRD's "???"
NO_UNIT = ("", "unknown", "pixel", "pixels", "voxel", "voxels", "none", "???")
_SYMBOLS = {name: unit for unit, names in LENGTH_UNITS.items() for name in names if len(name) <= 2}
_NAMES = {name.casefold(): unit for unit, names in LENGTH_UNITS.items() for name in names if len(name) > 2}


def length_unit(text: object) -> str | None:
    """A file's length unit in isoflow's one spelling per unit
    (:data:`LENGTH_UNITS`: ``m``, ``cm``, ``mm``, ``µm``, ``nm``, ``pm``,
    ``Å``, ``km``, ``in``, ``ft``, ``yd``, ``mi``); None for none said
    (:data:`NO_UNIT`); any other text as written (a unit isoflow does not
    know is still the file's).

    Parameters
    ----------
    text : object
        The unit as the file holds it: a string (ImageJ's ``\\u00B5m``
        escapes too), bytes, or None.

    Returns
    -------
    str or None

    Examples
    --------
    >>> length_unit("micron"), length_unit("micrometer"), length_unit("\\u00B5m"), length_unit("Millimeter")
    ('\u00b5m', '\u00b5m', '\u00b5m', 'mm')
    >>> length_unit("pixel") is None, length_unit(None) is None, length_unit("furlong")
    (True, True, 'furlong')
    """
    if text is None:
        return None
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    # ImageJ escapes what is not ASCII in its description as \uXXXX
    words = re.sub(r"\\u([0-9a-fA-F]{4})", lambda m: chr(int(m.group(1), 16)), str(text)).strip()
    if words.casefold() in NO_UNIT:
        return None
    return _SYMBOLS.get(words) or _NAMES.get(words.casefold(), words)


def unit_given(unit: object, where: str) -> str | None:
    """A length unit given to a writer (``unit=``) in isoflow's spelling
    (:func:`length_unit`: ``"micron"`` is ``"\u00b5m"``), None for None; one
    line naming it where it is no length unit isoflow knows
    (:data:`LENGTH_UNITS`): a writer stores it in the format's own
    spelling, which it knows only for those.

    Examples
    --------
    >>> unit_given("Millimeter", "a.nii"), unit_given(None, "a.nii") is None
    ('mm', True)
    >>> unit_given("pixel", "a.nii")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: a.nii: unit 'pixel' is not a length unit (one of m, cm, mm, \u00b5m, nm,
    pm, \u00c5, km, in, ft, yd, mi, in any spelling of length_unit)
    """
    if unit is None:
        return None
    spelled = length_unit(unit) if isinstance(unit, (str, bytes)) else None
    if spelled not in LENGTH_UNITS:
        raise IsoflowError(f"{where}: unit {unit!r} is not a length unit (one of {', '.join(LENGTH_UNITS)}, in any "
                           "spelling of length_unit)")
    return spelled


def unit_factor(unit: str, into: str) -> float:
    """How many of ``into`` one ``unit`` is, both in isoflow's spelling
    (:data:`LENGTH_UNITS`): the factor that turns a length in ``unit`` into
    one in ``into``.

    Parameters
    ----------
    unit, into : str
        Two of :data:`LENGTH_UNITS`.

    Returns
    -------
    float

    Examples
    --------
    >>> unit_factor("mm", "\u00b5m"), unit_factor("cm", "mm"), unit_factor("in", "mm")
    (1000.0, 10.0, 25.4)
    """
    return PICOMETRES[unit] / PICOMETRES[into]
