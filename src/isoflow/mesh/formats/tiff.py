"""TIFF: single images and multi-page stacks (tifffile).

Axes: a stack is read by tifffile as (pages, rows, columns) = (z, y, x) and
turned into isoflow's (x, y, z): column ``i``, row ``j``, page ``k`` is voxel
``(i, j, k)``; a single page is the 2D image (x, y), or, with ImageJ's z
``spacing`` (which isoflow writes for every 3D volume), a stack of one
slice. Axes of length 1 are kept (a volume one voxel wide). A stack without
ImageJ's axis names (tifffile's 'Q' or 'I' axis) is taken as z; a time
axis of several entries beside z (an OME-TIFF's or an ImageJ hyperstack's
``T``) is read as a fourth axis, (x, y, z, t) with voxel size 1 along t, the
4D volume ``info`` analyses; other axes (channels, RGB samples, the time of
a series of 2D images) must have length 1: a time series is not a z-stack,
however alike their pages look. One slice of several channels is what
tifffile's ``imwrite(f, stack, imagej=True)`` makes of a (slices, rows,
columns) stack, and Fiji opens it as channels: it is refused with the
command that saves the channels as slices, keeping the voxel size (an
OME-TIFF's PhysicalSizeX/Y/Z too) and the placement (ImageJ's origin, an
OME-TIFF's stage position). A file of several image series
(pages of different shapes, a second stack) is refused: which one is the
volume is not said by the file. A series that the NewSubfileType tag marks
as a reduced-resolution version of another (a thumbnail or preview stored
beside the stack) is no image of its own: :func:`full_images` leaves it out.

Grey stored as colour is read as that grey, as a PNG's is: RGB whose three
channels are equal, or grey, either with an alpha channel where the alpha
adds nothing to the grey (one opacity everywhere, or transparent exactly
where the grey is 0; another alpha is refused with the command that saves
it as the mask: :func:`.registry.check_alpha`); RGB whose channels differ
is refused; so are a stack's RGB pages, whether
their samples are interleaved or in planes. One RGB image whose samples
are stored as planes (PhotometricInterpretation 2, PlanarConfiguration 2)
is what tifffile's ``imwrite``, and scikit-image's and imageio's through
it, make of a (3 or 4, Y, X) array, and what all of them read back as that
array; image editors write RGB interleaved. Its planes are read as the
slices of a volume, the array tifffile reads, equal or not (a volume whose
slices are alike, or empty, is not read as 2D by its values), with a
warning that an image viewer shows them as the colours of one image (and,
where the colour planes are equal, the command that saves that grey image).

MinIsWhite (PhotometricInterpretation 0: 0 is shown white, as scanners,
fax-style 1-bit writers and Fiji's inverting LUT save masks) is read as
stored, with a warning: ImageJ keeps the stored values under an inverted
grey LUT (and reads a set 1-bit pixel as 255), and scikit-image and
tifffile keep them, so the object is the nonzero voxels that all of them
measure, shown dark; ``--label 0`` takes the voxels shown white (and
the warning, which offers it, is then not given: :func:`white_is_zero`).

Voxel size: x and y from the XResolution and YResolution tags (pitch =
1 / pixels per unit, in the file's resolution unit) by ImageJ's rule
(:func:`resolution_pitch`): 1 at the print resolution of 72 per inch that
Pillow and others give an image without a scale, with an ImageJ
description or without, and 1 where the file has neither a ResolutionUnit
tag nor an ImageJ description; in µm, 10000 times the centimetres, where
ImageJ converts them (:func:`micron_scale`: pixels per cm beside ImageJ's
``unit=um``, or a pixel of 0.0001 cm or less); z from ImageJ's
``spacing``; an OME-TIFF's PhysicalSizeX/Y/Z where given (in
PhysicalSizeX's unit, µm where not said, the others converted to it); 1
where absent.

Length unit: ImageJ's ``unit`` in its description (``micron``, ``um``
(ImageJ's spelling of µm), ``mm``, ...; ``pixel`` is none), the OME-XML
PhysicalSizeXUnit where an OME-TIFF gives a voxel size (µm where not
said), else the ResolutionUnit tag by ImageJ's rule (:func:`resolution_unit`:
centimetre, or inch unless at 72 dpi); µm where ImageJ converts
centimetres (:func:`micron_scale`).

Origin: ImageJ's calibration origin, ``xorigin``, ``yorigin`` and ``zorigin``
in its description (Fiji's Image > Properties "Origin"), in pixels of the
columns, rows and slices, that is of isoflow's x, y and z. ImageJ places
pixel coordinate ``p`` at ``(p - xorigin) * pixelWidth`` (its
``Calibration.getX``) and its Image > Adjust > Coordinates gives an image's
left edge as coordinate 0 and its right edge as its width: integer pixel
coordinates are pixel corners, so voxel 0's lowest corner is at
``-xorigin * pitch``, isoflow's origin, and an origin is written as
``xorigin = -origin / pitch`` (a key for each axis whose origin is not 0, as
ImageJ writes them). 0 where absent; a time axis's origin is 0. ImageJ's
``inverty`` (y upward from the bottom row) is not applied: y runs down the
rows, with a warning, and the y origin is then read as 0. An OME-TIFF's
first plane's PositionX/Y/Z, where given, is the place of voxel 0's
centre, as an OME-Zarr translation is: the origin is it less half a
voxel, converted to the voxel size's unit (a position in "reference
frame" units, the schema's default, is taken in that unit).

Written as an ImageJ hyperstack of uint8 0/1 with those tags, so that Fiji
opens it calibrated and placed, and a length unit given as ImageJ's
``unit`` (``um`` for \u00b5m, as ImageJ's ``FileSaver`` writes it; no key,
Fiji's "pixel", where none is given). Resolutions are rationals in TIFF: a pitch
is kept to about 9 digits, and so an origin read back through it. A name
ending in ``.ome.tif`` or ``.ome.tiff`` is written as an OME-TIFF instead
(:func:`_write_ome`): the voxel size and each plane's stage position in
its OME-XML, which OME readers place it by, as decimals.
"""

from __future__ import annotations

import functools
import json
import re
from fractions import Fraction
from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .registry import (
    HOLD_4D,
    RawVolume,
    ascii_unit,
    check_alpha,
    check_shape,
    colours_refused,
    import_library,
    length_unit,
    note,
    placement,
    quiet_logs,
    reading,
    refuse_empty,
    space_not_kept,
    stored_values,
    to_xyz,
)

X_RESOLUTION, Y_RESOLUTION, RESOLUTION_UNIT = 282, 283, 296
#: the largest numerator or denominator of a TIFF RATIONAL (two uint32)
RATIONAL_MAX = 2**32 - 1
#: how far a voxel size read back from its resolution tag may stray: TIFF's
#: rational holds about 9 digits wherever the size fits at all
RATIONAL_TOLERANCE = 1e-6
RESOLUTION_TAGS = (X_RESOLUTION, Y_RESOLUTION, RESOLUTION_UNIT)
#: TIFF's PhotometricInterpretation values whose first samples are grey or colour
MINISWHITE, MINISBLACK, RGB = 0, 1, 2
#: colour (or grey) samples per pixel, before the extra samples
COLOUR_SAMPLES = {MINISBLACK: 1, RGB: 3}
#: TIFF's ExtraSamples values of an alpha channel (associated, unassociated)
ALPHA = (1, 2)


def read(path: Path, dataset: str | None = None) -> RawVolume:
    tifffile = import_library("tifffile", "TIFF")
    where = str(path)
    # tifffile logs what it finds wrong before raising: the error line says it
    with reading(path, "TIFF"), quiet_logs("tifffile") as damage, tifffile.TiffFile(path) as tif:
        if not tif.series:
            raise IsoflowError(f"{where}: a TIFF without an image (damaged, or no pages)")
        images = full_images(tif.series)
        if len(images) > 1:
            shapes = ", ".join("x".join(map(str, s.shape)) for s in images[:5])
            raise IsoflowError(f"{where}: holds {len(images)} image series (shapes {shapes}"
                               f"{', ...' if len(images) > 5 else ''}); isoflow reads one volume: "
                               + (_pages_as_stack(where) if _one_page_each(images) else "save the stack on its own"))
        series = images[0]
        check_shape(series.shape[::-1], series.dtype, where)  # x first, as the image is read (to_xyz)
        page = series.keyframe
        try:
            data = series.asarray()
        except ValueError as exc:
            if "imagecodecs" not in str(exc):
                raise
            # tifffile decodes only zlib and PackBits itself: the file is whole, a package is missing
            raise IsoflowError(f"{where}: its pixels are {page.compression.name}-compressed, which tifffile decodes "
                               "only with the imagecodecs package: pip install imagecodecs") from None
        imagej = tif.imagej_metadata or {}
        tags = {t: page.tags[t].value for t in RESOLUTION_TAGS if t in page.tags}
        pitch = resolution_pitch(tags, tif.is_imagej, where)
        unit = length_unit(imagej.get("unit")) if tif.is_imagej else resolution_unit(tags)
        scale, z_scale = micron_scale(tags, pitch[0], imagej.get("unit"), tif.is_imagej)
        if scale != 1.0:
            pitch, unit = [p * scale for p in pitch], "\u00b5m"
        photometric, planar, extra = int(page.photometric), int(page.planarconfig) == 2, tuple(page.extrasamples)
        spacing = imagej.get("spacing")
        ome = tif.ome_metadata if tif.is_ome else None
        sizes, centres, ome_unit = _ome_placement(ome, where) if ome else ({}, {}, None)
        unit = ome_unit if sizes else unit  # (the OME voxel sizes replace the tags' and ImageJ's)
        axes, shape = _unsqueezed(series, spacing is not None)
        data = data.reshape(shape)
        damage = [d for d in damage if _tag_read(d)]
        if damage:
            # tifffile reads on past a page it cannot reach or metadata it
            # cannot parse: the stack it gives is then short (a 2D page
            # where ImageJ's header says 20 slices) or uncalibrated
            detail = re.sub(r"<[^<>]*>\s*", "", damage[0])  # tifffile's object names
            detail = re.sub(r"^raised \w+\((['\"])(.*)\1\)$", r"\2", detail)
            raise IsoflowError(f"{where}: not a readable TIFF file (cut short or damaged: {detail})")
    if _planes_of_one_image(axes, data.shape, photometric, planar):
        axes[axes.index("S")] = "Z"
        note(_planes_as_slices(where, np.moveaxis(data, axes.index("Z"), 0), extra))
    data, axes = _grey(data, axes, photometric, extra, where)
    if "Z" not in axes:  # a plain page stack: tifffile names its axis Q or I
        stack = [i for i, a in enumerate(axes) if a in "QI" and data.shape[i] > 1]
        if len(stack) == 1:
            axes[stack[0]] = "Z"
    names = ["x" if a == "X" else "y" if a == "Y" else "z" if a == "Z" else a for a in axes]
    try:
        vol = to_xyz(data, names, where)
    except IsoflowError as exc:
        if not _channels_of_one_slice(axes, data.shape):
            raise
        raise IsoflowError(f"{exc}; " + _as_slices(where, data.shape[axes.index("C")], ome)) from None
    if vol.ndim >= 3:
        depth = _spacing(imagej, where)
        # ImageJ scales a pixelDepth other than its default 1 (FileOpener.setCalibration)
        pitch.append(depth * z_scale if depth != 1.0 else depth)
    # ImageJ's origin counts its own pixels, so it scales by its own calibration, not by an OME size
    origin = _imagej_origin(imagej, pitch, where)
    if vol.ndim == 4:  # time keeps step 1, as a 4D NIfTI's does: a lattice axis, not seconds
        pitch.append(1.0)
        origin.append(0.0)
    pitch = [sizes.get(axis, p) for axis, p in zip("XYZT", pitch)]
    origin = [centres[axis] - p / 2 + 0.0 if axis in centres else o for axis, p, o in zip("XYZT", pitch, origin)]
    # which voxels are the object is said once the label selected is known
    said = functools.partial(white_is_zero, where) if photometric == MINISWHITE else None
    return RawVolume(vol, np.array(pitch), np.array(origin), unit=unit, said=said)


def resolution_pitch(tags: dict[int, object], imagej: bool = False, where: str = "TIFF") -> list[float]:
    """The x and y voxel size a TIFF's resolution tags give, by ImageJ's rule.

    ImageJ 1.x (``ij/io/TiffDecoder.java``, ``OpenIFD``, the cases
    ``X_RESOLUTION``, ``Y_RESOLUTION`` and ``RESOLUTION_UNIT``;
    ``ij/io/FileOpener.java``, ``decodeDescriptionString`` and
    ``setCalibration``) takes the pixel size as 1 / XResolution and
    1 / YResolution, but calls the image calibrated only where it has a
    unit: ResolutionUnit 1 (none) or 3 (centimetre), 2 (inch) unless the
    x resolution is exactly 72 per inch (the print resolution that
    Pillow, GIMP and most other writers give an image with no scale:
    ImageJ then sets the pixel size to 1, and an ImageJ description does
    not undo it), or an ImageJ description (whose ``unit``, or none,
    replaces the tag's). Without a
    ResolutionUnit tag and an ImageJ description the resolution is not
    read: TIFF's default unit, inch, is what a writer leaves unsaid.
    ImageJ's conversions of centimetres to microns are
    :func:`micron_scale`'s, applied to what this gives.

    Parameters
    ----------
    tags : dict of int to object
        The page's XResolution (282), YResolution (283) and ResolutionUnit
        (296) tag values where present: rationals as (numerator,
        denominator), the unit as its number.
    imagej : bool
        Whether the file has an ImageJ description (``ImageJ=...``).
    where : str
        The file, for the line that refuses a resolution that is no
        rational.

    Returns
    -------
    list of float
        The x and y pitch in the file's unit; 1 for an uncalibrated image
        and for a resolution that is not positive (ImageJ ignores it).

    Examples
    --------
    >>> resolution_pitch({282: (72, 1), 283: (72, 1), 296: 2})
    [1.0, 1.0]
    >>> resolution_pitch({282: (300, 1), 283: (300, 1), 296: 2})
    [0.0033333333333333335, 0.0033333333333333335]
    >>> resolution_pitch({282: (2, 1), 283: (4, 1)}, imagej=True)
    [0.5, 0.25]
    >>> resolution_pitch({282: (2, 1), 283: (2, 1)})
    [1.0, 1.0]
    """
    pitch = [1.0, 1.0]
    for i, tag in enumerate((X_RESOLUTION, Y_RESOLUTION)):
        if tag not in tags:
            continue
        value = tags[tag]
        try:
            numerator, denominator = (float(v) for v in value)  # type: ignore[attr-defined]
        except (TypeError, ValueError):
            name = "XResolution" if tag == X_RESOLUTION else "YResolution"
            raise IsoflowError(f"{where}: the TIFF's {name} {value!r} is not a rational") from None
        scale = numerator / denominator if denominator else 0.0
        if np.isfinite(scale) and scale > 0:
            pitch[i] = 1.0 / scale
    unit = tags.get(RESOLUTION_UNIT)
    unit = int(unit) if isinstance(unit, (int, np.integer)) else None
    if unit == 2 and pitch[0] == 1.0 / 72.0:
        return [1.0, 1.0]
    return pitch if imagej or unit in (1, 2, 3) else [1.0, 1.0]


def resolution_unit(tags: dict[int, object]) -> str | None:
    """The length unit of a TIFF's resolution tags without an ImageJ
    description, by ImageJ's rule (see :func:`resolution_pitch`):
    centimetre for ResolutionUnit 3, inch for 2 unless at the print
    resolution of 72 dpi (no scale), none otherwise (1, or no tag).

    Examples
    --------
    >>> resolution_unit({282: (300, 1), 283: (300, 1), 296: 2}), resolution_unit({282: (72, 1), 296: 2})
    ('in', None)
    >>> resolution_unit({282: (1000, 1), 296: 3}), resolution_unit({282: (1000, 1), 296: 1})
    ('cm', None)
    """
    unit = tags.get(RESOLUTION_UNIT)
    unit = int(unit) if isinstance(unit, (int, np.integer)) else None
    if unit == 3:
        return "cm"
    if unit == 2 and resolution_pitch(tags) != [1.0, 1.0]:
        return "in"
    return None


#: micrometres per centimetre, the factor of ImageJ's conversions
MICRONS_PER_CM = 10000.0


def micron_scale(tags: dict[int, object], pitch: float, unit: object = None, imagej: bool = False) -> tuple[float, float]:
    """The factors by which ImageJ turns a TIFF's centimetre calibration
    into micrometres: of the x and y pitch, and of a z spacing other than 1.

    ImageJ 1.x (``ij/io/FileOpener.java``, imagej/ImageJ commit 03dc240)
    converts in two places, and nowhere else (no other unit, no inch, no
    ``mm``):

    * ``decodeDescriptionString``, for a file with an ImageJ description,
      whose ``unit`` replaces the tag's::

          String dsUnit = props.getProperty("unit","");
          if ("cm".equals(fi.unit) && "um".equals(dsUnit)) {
              fi.pixelWidth *= 10000;
              fi.pixelHeight *= 10000;
          }
          fi.unit = dsUnit;

      ``fi.unit`` is ``"cm"`` for ResolutionUnit 3 only
      (``ij/io/TiffDecoder.java``, ``OpenIFD``, case ``RESOLUTION_UNIT``):
      the tags give pixels per centimetre, the description says µm, and
      so the pitch is 10000 times 1 / resolution, µm; z is not scaled (the
      description's ``spacing`` is in its own unit). Only the text ``um``
      is matched, ImageJ's own spelling of µm (``micron`` or ``\u00B5m``
      are not, and stay 1 / resolution).
    * ``setCalibration``, after it, with ``Prefs.convertToMicrons`` (true
      unless changed: ``ij/Prefs.java``)::

          if (Prefs.convertToMicrons && fi.pixelWidth<=0.0001 && fi.unit.equals("cm")) {
              fi.pixelWidth *= 10000.0;
              fi.pixelHeight *= 10000.0;
              if (fi.pixelDepth!=1.0)
                  fi.pixelDepth *= 10000.0;
              fi.unit = "um";
          }

      so a centimetre calibration of 1 µm or less per pixel (ResolutionUnit
      3 without an ImageJ description, or a description whose ``unit`` is
      ``cm``) is read in µm, its z spacing too unless it is 1 (ImageJ's
      ``pixelDepth`` where no spacing is given).

    Parameters
    ----------
    tags : dict of int to object
        The page's resolution tags, as :func:`resolution_pitch` takes them.
    pitch : float
        The x pitch :func:`resolution_pitch` gives (ImageJ's
        ``pixelWidth``).
    unit : object
        The ImageJ description's ``unit`` as written (None where absent).
    imagej : bool
        Whether the file has an ImageJ description.

    Returns
    -------
    tuple of float
        The factor of the x and y pitch and that of a z spacing other than
        1: 1 where ImageJ does not convert; where it does, the unit is µm.

    Examples
    --------
    >>> micron_scale({282: (20000, 1), 283: (20000, 1), 296: 3}, 5e-05, "um", imagej=True)
    (10000.0, 1.0)
    >>> micron_scale({282: (20000, 1), 283: (20000, 1), 296: 3}, 5e-05)
    (10000.0, 10000.0)
    >>> micron_scale({282: (20000, 1), 283: (20000, 1), 296: 3}, 5e-05, "micron", imagej=True)
    (1.0, 1.0)
    >>> micron_scale({282: (20, 1), 283: (20, 1), 296: 3}, 0.05)
    (1.0, 1.0)
    """
    code = tags.get(RESOLUTION_UNIT)
    cm = isinstance(code, (int, np.integer)) and int(code) == 3
    if imagej and cm and unit == "um":
        return MICRONS_PER_CM, 1.0
    said = unit if imagej else "cm" if cm else None
    if said == "cm" and 0 < pitch <= 0.0001:
        return MICRONS_PER_CM, MICRONS_PER_CM
    return 1.0, 1.0


def _grey(data: np.ndarray, axes: list[str], photometric: int, extra: tuple, where: str) -> tuple[np.ndarray, list[str]]:
    """``data`` without its samples axis ``S`` where the samples are grey
    stored as colour, as a PNG's are read (see :mod:`.png`): RGB whose
    three channels are equal, or grey, either with an alpha that adds
    nothing to the grey (:func:`.registry.check_alpha`). Other samples are
    left for :func:`to_xyz` to refuse as channels.

    The samples of a stack's RGB pages are read so whether they are stored
    interleaved or as planes: there the planes cannot be slices, the pages
    are (one RGB image in planes is :func:`_planes_of_one_image`)."""
    colours = COLOUR_SAMPLES.get(photometric)
    if "S" not in axes or colours is None or not all(int(e) in ALPHA for e in extra):
        return data, axes
    s = axes.index("S")
    samples = np.moveaxis(data, s, 0)
    if samples.shape[0] != colours + len(extra):
        return data, axes
    grey = samples[0]
    if not (samples[:colours] == grey).all():
        raise colours_refused(where, "RGB", "a grey (8- or 16-bit) TIFF")
    for i, kind in enumerate(extra, start=colours):
        check_alpha(grey, samples[i], where, f"TIFF ExtraSamples {int(kind)}", _command(where, _alpha_as_grey, "_alpha"))
    return np.ascontiguousarray(grey), axes[:s] + axes[s + 1:]


def _alpha_as_grey(src: str, dst: str) -> str:
    """The tifffile call that saves the last sample (the alpha) of the TIFF
    ``src`` as the grey TIFF ``dst``, keeping its resolution tags."""
    return ("t = tifffile.TiffFile(" + src + "); s = t.series[0]; p = t.pages[0]; tifffile.imwrite(" + dst
            + ', numpy.take(s.asarray(), -1, axis=s.axes.index("S")), photometric="minisblack", '
            "resolution=p.resolution, resolutionunit=p.resolutionunit)")


def _planes_of_one_image(axes: list[str], shape: tuple[int, ...], photometric: int, planar: bool) -> bool:
    """Whether the file is one RGB image whose samples are stored as planes
    (PlanarConfiguration 2), the samples being its only axis beside the
    rows and columns with more than one entry: what tifffile, and
    scikit-image's and imageio's ``imsave`` through it, make of a (3 or 4,
    Y, X) array, which all of them read back as that array."""
    return planar and photometric == RGB and "S" in axes and all(n == 1 or a in "SYX" for a, n in zip(axes, shape))


def _planes_as_slices(where: str, planes: np.ndarray, extra: tuple) -> str:
    """The warning for one RGB image stored in ``planes`` (the first axis),
    read as the slices of a volume: an image viewer shows them as the
    colours of one image, which a user who meant that image must know; where
    its colour planes are equal, the image shown is grey, and the line
    gives the command that saves it as that grey image."""
    kind = "RGBA" if len(planes) == 4 and extra and int(extra[0]) in ALPHA else "RGB"
    said = (f"{where}: one {kind} image stored in {len(planes)} separate planes (PhotometricInterpretation 2, RGB; "
            f"PlanarConfiguration 2, separate), as tifffile, scikit-image and imageio save a ({len(planes)}, rows, "
            "columns) array, is read as the slices of a volume, the array they read back; an image viewer shows "
            "the planes as the colours of one image")
    if not (planes[1:3] == planes[0]).all():
        return said
    return said + "; its colour planes are equal, shown as one grey image: " + _resaved(
        where, "if it is that image", lambda src, dst: f"t = tifffile.TiffFile({src}); p = t.pages[0]; "
        f"tifffile.imwrite({dst}, p.asarray()[0], resolution=p.resolution, resolutionunit=p.resolutionunit)",
        "save its first plane as a grey image", "_grey")


def white_is_zero(where: str, label: object = None) -> str | None:
    """The warning for a MinIsWhite file, whose viewers show 0 as white:
    its values are kept as stored, as ImageJ (an inverted grey LUT over
    the stored values; 1-bit pixels set read as 255), scikit-image and
    tifffile keep them, so that the object is what every one of them
    measures; but what a viewer shows as the object may be the 0s.

    Parameters
    ----------
    where : str
        The file, as messages name it.
    label : number, optional
        The label selected. With none, the warning offers ``--label 0``
        for the voxels shown white; with another, it says that the label
        is a stored value; with 0 itself the user has chosen the voxels
        shown white, and nothing is said (None).

    Returns
    -------
    str or None
        The warning's one line, or None.

    Examples
    --------
    >>> white_is_zero("m.tif").endswith("--label 0 (label=0) takes the voxels shown white instead")
    True
    >>> white_is_zero("m.tif", label=1).endswith("so label 1 selects the voxels stored as 1")
    True
    >>> white_is_zero("m.tif", label=0) is None
    True
    """
    if label is not None and label == 0:
        return None
    said = (f"{where}: stored MinIsWhite (TIFF PhotometricInterpretation 0: 0 is shown white); its values are read "
            "as stored, as ImageJ, scikit-image and tifffile read them, ")
    if label is not None:
        return said + f"so label {label} selects the voxels stored as {label}"
    return said + ("so a mask's object is its nonzero voxels, shown dark; --label 0 (label=0) takes the voxels shown "
                   "white instead")


def _imagej_origin(imagej: dict, pitch: list[float], where: str) -> list[float]:
    """The world position of voxel 0's lowest corner per spatial axis from
    ImageJ's ``xorigin``, ``yorigin`` and ``zorigin`` (pixels; 0 where
    absent): ImageJ's pixel coordinate 0 is that corner, at ``-origin *
    pitch``. ImageJ's ``inverty`` runs y up from the bottom row, which a
    positive step down the rows cannot say: y is then read from 0."""
    origin = [-_imagej_number(imagej, f"{axis}origin", where, 0.0) * p for axis, p in zip("xyz", pitch)]
    if str(imagej.get("inverty", "")).lower() == "true":
        note(f"{where}: ImageJ's inverted y (inverty) is not applied: y runs down the rows, from 0")
        origin[1] = 0.0
    return [o + 0.0 for o in origin]  # no -0.0 from an origin of 0


#: the tags whose values shape the pixels or hold what isoflow reads (the
#: ImageJ and OME metadata in ImageDescription 270, the resolution)
READ_TAGS = frozenset((254, 256, 257, 258, 259, 262, 266, 270, 273, 277, 278, 279, 282, 283, 284, 296, 317, 322, 323,
                       324, 325, 338, 339, 347))


def _tag_read(message: str) -> bool:
    """Whether an error tifffile logged is damage to what is read: any but
    a tag it could not read that isoflow does not use (a vendor's private
    tag pointing past the end of the file leaves the pixels whole)."""
    tag = re.search(r"TiffTag (\d+) ", message)
    return tag is None or int(tag.group(1)) in READ_TAGS


def full_images(series: list) -> list:
    """The image series of a TIFF less those its NewSubfileType tag marks
    as a reduced-resolution version of another image (bit 0: a
    thumbnail or preview that a microscope or scanner stores beside the
    stack, as tifffile, scikit-image and Fiji read past it); all of them
    where every one is so marked.

    Parameters
    ----------
    series : list of tifffile.TiffPageSeries
        ``TiffFile.series``.

    Returns
    -------
    list of tifffile.TiffPageSeries
        Those that are images in their own right, in the file's order.

    Examples
    --------
    >>> import io, tifffile
    >>> buffer = io.BytesIO()
    >>> with tifffile.TiffWriter(buffer) as tif:
    ...     tif.write(np.zeros((4, 6, 5), np.uint8), photometric="minisblack")
    ...     tif.write(np.zeros((2, 2), np.uint8), subfiletype=1)  # a thumbnail
    >>> with tifffile.TiffFile(io.BytesIO(buffer.getvalue())) as tif:
    ...     [s.shape for s in tif.series], [s.shape for s in full_images(tif.series)]
    ([(4, 6, 5), (2, 2)], [(4, 6, 5)])
    """
    full = [s for s in series if not int(getattr(s.keyframe, "subfiletype", 0) or 0) & 1]
    return full or list(series)


def _one_page_each(series) -> bool:
    """Whether every series is one 2D page of one shape and type: a stack
    written a page at a time (tifffile's ``TiffWriter.write`` per slice),
    which may also be images of different things, so it is not read as z."""
    return all(len(s.shape) == 2 and s.shape == series[0].shape and s.dtype == series[0].dtype for s in series)


def _pages_as_stack(where: str) -> str:
    """The line that saves one-page series as one z-stack, if they are one."""
    return ("each a page of one shape, as a stack written a page at a time is; "
            + _as_stack(where, ", key=slice(None)", "if its pages are the slices of one volume"))


def _as_stack(where: str, key: str, condition: str) -> str:
    """The advice, under ``condition``, to save the file's pixels (read
    with tifffile's ``imread`` arguments ``key``) as one grey z-stack, with
    the command that does it."""
    return _resaved(where, condition, lambda src, dst: f"tifffile.imwrite({dst}, tifffile.imread({src}{key}), "
                                                       'photometric="minisblack")')


def _channels_of_one_slice(axes: list[str], shape: tuple[int, ...]) -> bool:
    """Whether the only axis beside the rows and columns with more than one
    entry is the channels: what tifffile's ``imwrite(..., imagej=True)``
    makes of a (slices, rows, columns) array (ImageJ's description then
    says ``channels=``, and Fiji opens it as channels too)."""
    return "C" in axes and all(n == 1 or a in "CYX" for a, n in zip(axes, shape))


def _as_slices(where: str, channels: int, ome: str | None = None) -> str:
    """The advice to save a file of ``channels`` channels and one slice as
    that many slices, keeping its resolution tags and ImageJ metadata
    (tifffile's ``metadata={'axes': 'ZYX'}``), with the command that does
    it; an OME-TIFF (``ome``, its OME-XML) whose voxel size is its
    PhysicalSizeX/Y/Z, or that gives a stage position, is saved as an
    OME-TIFF with those (:func:`_ome_stage`), which its resolution tags
    and ImageJ metadata need not hold."""
    sizes = _ome_sizes(ome)
    stage = _ome_stage(ome, where, channels)
    if sizes or stage:
        kept = ", ".join([f'"{name}": {float(value)!r}' if not name.endswith("Unit") else f'"{name}": {json.dumps(value)}'
                          for name, value in sizes.items()] + stage)
        return _resaved(where, f"if its {channels} channels are the slices of one volume",
                        lambda src, dst: f"tifffile.imwrite({dst}, tifffile.imread({src}), ome=True, "
                                         f'metadata={{"axes": "ZYX", {kept}}})', ome=True)
    return _resaved(where, f"if its {channels} channels are the slices of one volume",
                    lambda src, dst: f"t = tifffile.TiffFile({src}); p = t.pages[0]; tifffile.imwrite({dst}, "
                                     "t.asarray(), imagej=t.is_imagej, resolution=p.resolution, "
                                     'resolutionunit=p.resolutionunit, metadata={**(t.imagej_metadata or {}), '
                                     '"axes": "ZYX"})')


def _ome_stage(ome: str | None, where: str, slices: int) -> list[str]:
    """tifffile's ``Plane`` metadata, as the text of a dict entry, that
    places ``slices`` slices at an OME-TIFF's stage position (``ome``, its
    OME-XML): the first plane's PositionX/Y/Z, the one the reader takes,
    in PhysicalSizeX's unit, and each further slice one PhysicalSizeZ
    higher (none where the file gives no position)."""
    sizes, centres, _ = _ome_placement(ome, where, quiet=True)
    if not centres:
        return []
    pixels = _ome_pixels(ome)
    unit = json.dumps(pixels.get("PhysicalSizeXUnit") or "\u00b5m")
    entries = []
    for axis, centre in centres.items():
        # each slice's own place, for the readers that place planes one by one
        places = (f"[{centre!r} + {sizes[axis]!r} * k for k in range({slices})]" if axis == "Z" and "Z" in sizes
                  else f"[{centre!r}] * {slices}")
        entries.append(f'"Position{axis}": {places}, "Position{axis}Unit": [{unit}] * {slices}')
    return [f'"Plane": {{{", ".join(entries)}}}']


def _resaved(where: str, condition: str, write, saved: str = "save them as one stack", suffix: str = "_stack",
             ome: bool = False) -> str:
    """The advice, under ``condition``, to ``saved`` (save the file as one
    stack) beside it (``NAME_stack.tif``, the stem ending in ``suffix``;
    ``NAME_stack.ome.tif`` where ``ome``, the write an OME-TIFF's) and give
    that, with the ``python -c`` command whose tifffile call
    ``write(source, stack)`` (the two paths as Python literals) writes it."""
    return f"{condition}, {saved} and give that: {_command(where, write, suffix, ome)}"


def _command(where: str, write, suffix: str, ome: bool = False) -> str:
    """The ``python -c`` command whose tifffile call ``write(source,
    saved)`` (the two paths as Python literals) saves the TIFF ``where``
    beside it as :func:`resaved_name` names it."""
    import shlex

    code = f"import numpy, tifffile; {write(json.dumps(where), json.dumps(resaved_name(where, suffix, ome)))}"
    return f"python -c {shlex.quote(code)}"


def resaved_name(where: str, suffix: str, ome: bool = False) -> str:
    """The path beside the TIFF ``where`` of its re-saved copy: its name
    without the ``.tif``/``.tiff`` and an OME-TIFF's ``.ome`` before it,
    then ``suffix``, then ``.ome.tif`` where the copy is an OME-TIFF (the
    name OME readers, and tifffile itself, tell one by), else ``.tif``.

    Parameters
    ----------
    where : str
        The TIFF as given.
    suffix : str
        What the copy's name adds (``_stack``, ``_grey``, ``_alpha``).
    ome : bool
        Whether the copy is written as an OME-TIFF.

    Returns
    -------
    str

    Examples
    --------
    >>> resaved_name("data/c.ome.tif", "_stack", ome=True), resaved_name("data/c.ome.tiff", "_grey")
    ('data/c_stack.ome.tif', 'data/c_grey.tif')
    >>> resaved_name("scan.TIF", "_stack")
    'scan_stack.tif'
    """
    stem = Path(where).stem
    if stem.lower().endswith(".ome"):  # c.ome.tif: c_stack.ome.tif, not c.ome_stack.tif
        stem = stem[:-len(".ome")]
    return str(Path(where).with_name(stem + suffix + (".ome.tif" if ome else ".tif")))


#: metres per length unit of OME-XML (``UnitsLength``, schema 2016-06), and
#: "um", which writers put for micrometres though the schema spells it "µm"
OME_METRES = {
    "Ym": 1e24, "Zm": 1e21, "Em": 1e18, "Pm": 1e15, "Tm": 1e12, "Gm": 1e9, "Mm": 1e6, "km": 1e3, "hm": 1e2,
    "dam": 1e1, "m": 1.0, "dm": 1e-1, "cm": 1e-2, "mm": 1e-3, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "um": 1e-6,
    "nm": 1e-9, "pm": 1e-12, "fm": 1e-15, "am": 1e-18, "zm": 1e-21, "ym": 1e-24, "\u00c5": 1e-10,
    "thou": 2.54e-5, "li": 2.54e-2 / 12, "in": 2.54e-2, "ft": 0.3048, "yd": 0.9144, "mi": 1609.344,
    "ua": 149597870700.0, "ly": 9460730472580800.0, "pc": 3.0856775814913673e16, "pt": 2.54e-2 / 72,
}
#: OME-XML's unit of a stage position not tied to a length (the schema's
#: default for ``PositionXUnit``): taken as the voxel size's unit
REFERENCE_FRAME = "reference frame"


def _ome_placement(xml: str | None, where: str, quiet: bool = False) -> tuple[dict[str, float], dict[str, float],
                                                                             str | None]:
    """An OME-TIFF's voxel size and voxel 0's centre per axis (``X``,
    ``Y``, ``Z``), where given: the ``Pixels`` element's PhysicalSize
    attributes, the file's own calibration, which the resolution tags
    need not carry, and the first plane's PositionX/Y/Z (the plane of
    ``TheZ``, ``TheT`` and ``TheC`` 0), the stage's place of the image.

    Both are in the unit of PhysicalSizeX (the schema's default, µm, where
    not said), the others converted to it: a PhysicalSizeZ in nm beside an
    x in µm is 1000 times smaller. A position is the place of voxel 0's
    centre, as an OME-Zarr translation is, and as BigStitcher places a
    tile at its stage position (imglib2's pixel coordinates are pixel
    centres); one in "reference frame" units, the schema's default, is
    taken in the voxel size's unit. Without any PhysicalSize the voxel
    size is in no length unit: a position in one is not read, with a
    warning (``quiet``: none, for a second reading of the same XML). The
    third item is that unit (:func:`length_unit`)."""
    pixels = _ome_pixels(xml)
    if pixels is None:
        return {}, {}, None
    unit = pixels.get("PhysicalSizeXUnit") or "\u00b5m"
    sizes = {}
    for axis in "XYZ":
        size = _ome_length(pixels, f"PhysicalSize{axis}", unit, where)
        if size is None:
            continue
        if not size > 0:
            raise IsoflowError(f"{where}: OME-XML's PhysicalSize{axis} {pixels.get(f'PhysicalSize{axis}')!r} is not "
                               "a positive voxel size")
        sizes[axis] = size
    planes = pixels.findall("{*}Plane")
    first = [p for p in planes if all(p.get(f"The{a}", "0") == "0" for a in "ZTC")]
    centres, unplaced = {}, []
    for axis in "XYZ" if planes else "":
        plane = (first or planes)[0]
        centre = _ome_length(plane, f"Position{axis}", unit, where)
        if centre is not None and not sizes and plane.get(f"Position{axis}Unit", REFERENCE_FRAME) != REFERENCE_FRAME:
            unplaced.append(axis)
        elif centre is not None:
            centres[axis] = centre
    if unplaced and not quiet:
        note(_positions_without_size(where, unplaced, (first or planes)[0]))
    return sizes, centres, length_unit(unit)


def _positions_without_size(where: str, axes: list[str], plane) -> str:
    """The warning for stage positions in a length unit in an OME-TIFF that
    gives no PhysicalSize: its voxels are of no known length, so the
    positions have no place in them (a position in mm beside voxels of size
    1 in no unit would be read as 1500 voxels for 1.5 mm)."""
    said = ", ".join(f"Position{a} {plane.get(f'Position{a}')} {plane.get(f'Position{a}Unit')}" for a in axes)
    return (f"{where}: OME-XML's {said} {'is' if len(axes) == 1 else 'are'} not read: the file gives no "
            "PhysicalSizeX/Y/Z, so its voxel size is in no length unit to place a position in; "
            f"{', '.join(a.lower() for a in axes)} placed as without {'it' if len(axes) == 1 else 'them'}")


def _ome_sizes(xml: str | None) -> dict[str, str]:
    """The ``Pixels`` element's PhysicalSizeX/Y/Z attributes and their
    units, as an OME-TIFF's XML ``xml`` writes them (none where absent or
    unreadable)."""
    pixels = _ome_pixels(xml)
    names = [f"PhysicalSize{axis}{unit}" for axis in "XYZ" for unit in ("", "Unit")]
    return {} if pixels is None else {name: pixels.get(name) for name in names if pixels.get(name) is not None}


def _ome_pixels(xml: str | None):
    """The ``Pixels`` element of OME-XML ``xml`` (the first image's), or
    None where there is none or the XML is unreadable."""
    import xml.etree.ElementTree as ET

    try:
        return ET.fromstring(xml or "").find(".//{*}Pixels")
    except ET.ParseError:
        return None  # (unreadable OME-XML: the tags and ImageJ's spacing, as for any TIFF)


def _ome_length(element, name: str, unit: str, where: str) -> float | None:
    """The OME-XML length attribute ``name`` of ``element`` in ``unit`` (None
    where absent), or one line naming it where it is no finite number or
    its unit is none that converts to ``unit``."""
    value = element.get(name)
    if value is None:
        return None
    try:
        length = float(value)
    except ValueError:
        raise IsoflowError(f"{where}: OME-XML's {name} {value!r} is not a number") from None
    if not np.isfinite(length):
        raise IsoflowError(f"{where}: OME-XML's {name} {value!r} is not a finite number")
    own = element.get(f"{name}Unit") or ("\u00b5m" if name.startswith("Physical") else REFERENCE_FRAME)
    if own in (unit, REFERENCE_FRAME):
        return length
    if own not in OME_METRES or unit not in OME_METRES:
        raise IsoflowError(f"{where}: OME-XML's {name}Unit {own!r} does not convert to PhysicalSizeXUnit {unit!r}, "
                           "the voxel size's unit")
    return length * OME_METRES[own] / OME_METRES[unit]


def _unsqueezed(series, stack: bool) -> tuple[list[str], list[int]]:
    """The series' axes and shape without its axes of length 1, but for
    the rows and columns (tifffile drops those too: a volume one voxel wide
    would lose an axis) and, in a ``stack`` (ImageJ's z ``spacing`` is
    given, as isoflow writes every 3D volume), the slices: a stack of one
    slice is a volume one voxel thick, not a 2D image."""
    axes, shape = series.get_axes(False).upper(), series.get_shape(False)
    keep = [i for i, (a, n) in enumerate(zip(axes, shape)) if n > 1 or a in "YX" or (a == "Z" and stack)]
    return [axes[i] for i in keep], [shape[i] for i in keep]


def _spacing(imagej: dict, where: str) -> float:
    """The z voxel size from ImageJ's ``spacing`` (1 where absent), or one
    line naming that field where it is no positive size (a negative one,
    slices running backwards, would need the stack turned to be placed)."""
    size = _imagej_number(imagej, "spacing", where, 1.0)
    if size <= 0:
        raise IsoflowError(f"{where}: ImageJ's spacing {imagej['spacing']!r} is not a positive voxel size")
    return size


def _imagej_number(imagej: dict, key: str, where: str, default: float) -> float:
    """ImageJ's number ``key`` (its z ``spacing``, an ``xorigin``), ``default``
    where absent."""
    value = imagej.get(key)
    if value is None or value == "":
        return default
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise IsoflowError(f"{where}: ImageJ's {key} {value!r} is not a number") from None
    if not np.isfinite(number):
        raise IsoflowError(f"{where}: ImageJ's {key} {value!r} is not a finite number")
    return number


def _resolution_rational(pitch: float) -> tuple[int, int]:
    """1 / ``pitch`` as a TIFF RATIONAL, the fraction tifffile writes for
    that float: the nearest whose numerator and denominator are both 32-bit
    unsigned integers; ``(0, 1)`` where the resolution is below the smallest
    such fraction, and no fraction where it is above the largest."""
    f = Fraction(1 / pitch)
    largest = min(RATIONAL_MAX, int(RATIONAL_MAX / f))  # the numerator must fit too
    if largest < 1:
        raise OverflowError(f"1 / {pitch} is past {RATIONAL_MAX}")
    f = f.limit_denominator(largest)
    return f.numerator, f.denominator


def _check_resolution(path: Path, obj: DigitalObject) -> None:
    """Refuse a voxel size that the resolution tags cannot hold, before
    anything is written: tifffile fails on a pitch too fine with a
    ValueError, and writes one too coarse as a resolution of 0, which
    readers (ImageJ, isoflow) take as no calibration, a pitch of 1."""
    spacing, _ = placement(obj)
    for axis, tag, p in zip("xy", ("XResolution", "YResolution"), spacing):
        try:
            num, den = _resolution_rational(float(p))
        except OverflowError:
            num, den = 0, 1
        if num == 0 or abs(den / num - p) > RATIONAL_TOLERANCE * p:
            back = "" if num == 0 else f" (it would be read back as {den / num:.6g})"
            raise IsoflowError(f"{path}: TIFF's {tag} holds 1 / voxel size as a ratio of two 32-bit integers, which "
                               f"cannot hold the {axis} voxel size {float(p):.6g}{back}; write .nrrd, .h5 or .npz, "
                               "which keep it, or use another length unit")


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    if obj.ndim not in (2, 3):
        raise IsoflowError(f"{path}: a TIFF holds a 2D image or a 3D stack, this object is {obj.ndim}D; {HOLD_4D}")
    refuse_empty(path, obj.volume.shape, "TIFF")  # tifffile fails on it with a ValueError of its own
    space_not_kept(path, "TIFF", space)
    if not is_ome_name(path.name):  # OME-XML writes the sizes as decimals, not as TIFF rationals
        _check_resolution(path, obj)
    elif obj.ndim == 3 and obj.volume.shape[2] == 1:
        # a 2D microscope image often carries a PhysicalSizeZ too, so the
        # reader cannot take one as the mark of a stack
        note(f"{path}: an OME-TIFF of one slice is read back as a 2D image (its OME-XML says a stack of one slice "
             "as it says a 2D image); write .tif, .nrrd, .h5 or .npz to keep the volume one voxel thick")


def is_ome_name(name: str) -> bool:
    """Whether a file name is an OME-TIFF's (``.ome.tif``, ``.ome.tiff``),
    which OME readers (Bio-Formats, QuPath, BigStitcher) place by its
    OME-XML.

    Examples
    --------
    >>> is_ome_name("scan.ome.tif"), is_ome_name("SCAN.OME.TIFF"), is_ome_name("scan.tif")
    (True, True, False)
    """
    return name.lower().endswith((".ome.tif", ".ome.tiff"))


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    tifffile = import_library("tifffile", "TIFF")
    if is_ome_name(name or path.name):
        _write_ome(tifffile, path, obj, unit)
        return
    spacing, corner = placement(obj)
    data = stored_values(np.ascontiguousarray(obj.volume.T))  # (z,) y, x
    metadata: dict[str, str | float] = {"axes": "TZCYXS"}  # all six: tifffile reads a last axis of length 1 as samples, not as x
    if obj.ndim == 3:
        metadata["spacing"] = float(spacing[2])
    if unit is not None:
        metadata["unit"] = ascii_unit(unit)
    for axis, c, p in zip("xyz", corner, spacing):
        if c != 0:  # ImageJ writes an origin of 0 as no key
            metadata[f"{axis}origin"] = float(-c / p)
    z, y, x = data.shape if obj.ndim == 3 else (1, *data.shape)
    resolution = (_resolution_rational(spacing[0]), _resolution_rational(spacing[1]))  # as check() found them
    tifffile.imwrite(path, data.reshape(1, z, 1, y, x, 1), imagej=True, resolution=resolution, metadata=metadata)


def _write_ome(tifffile, path: Path, obj: DigitalObject, unit: str | None) -> None:
    """Write ``obj`` as an OME-TIFF: the voxel size as PhysicalSizeX/Y/Z and
    each plane's stage position as PositionX/Y/Z, the centre of its first
    voxel (the place :func:`_ome_placement` reads), all in ``unit``, which
    OME-XML spells as isoflow does (``µm``, ``mm``, ``Å``, ...); without
    one, OME's ``pixel``, which reads back as no unit (the schema's
    default, µm, would give the object a unit it has not)."""
    spacing, corner = placement(obj)
    centre = [float(c + p / 2) for c, p in zip(corner, spacing)]
    data = stored_values(np.ascontiguousarray(obj.volume.T))  # (z,) y, x
    planes = data.shape[0] if obj.ndim == 3 else 1
    said = unit or "pixel"
    metadata: dict[str, object] = {"axes": "ZYX" if obj.ndim == 3 else "YX"}
    plane: dict[str, list] = {}
    for i, axis in enumerate("XYZ"[:obj.ndim]):
        metadata[f"PhysicalSize{axis}"], metadata[f"PhysicalSize{axis}Unit"] = float(spacing[i]), said
        step = float(spacing[i]) if axis == "Z" else 0.0  # each slice at its own height
        plane[f"Position{axis}"] = [centre[i] + step * k for k in range(planes)]
        plane[f"Position{axis}Unit"] = [said] * planes
    metadata["Plane"] = plane
    tifffile.imwrite(path, data, ome=True, photometric="minisblack", metadata=metadata)
