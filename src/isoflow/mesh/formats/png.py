"""PNG: 2D masks and label images (Pillow).

PNG is what many 2D segmentations are saved as: Cellpose's ``_cp_masks.png``
(16-bit cell numbers), palette PNGs whose indices are the classes (PASCAL
VOC), 8-bit masks. Axes: row ``j``, column ``i`` is pixel ``(i, j)``
(isoflow's (x, y), as a TIFF page). Modes: bilevel (``1``) as bool; 8-,
16- and 32-bit grey (``L``, ``I;16``, ``I``) as their integers; palette
(``P``) as the indices, not the colours; grey stored as colour (``RGB``,
``RGBA``, ``LA`` whose colour channels are equal) as that grey, where
the alpha adds nothing to it: one opacity everywhere, or transparent
exactly where the grey is 0; an alpha that shows other pixels than the
grey's (black ink on a transparent sheet) is refused, with the command
that saves the alpha as the mask (:func:`.registry.check_alpha`).
Colours that differ are refused: a colour-coded image is a picture of
labels, whose numbering its file does not say. So is colour or
grey with alpha at 16 bits a channel, which Pillow reads as 8 (label 300
would be 1, labels 1 to 255 would be 0). An animated PNG
(several frames) is refused. The pixel size is 1: PNG's ``pHYs`` is a
print resolution (pixels per metre), not a microscope's calibration.

Written (2D only) as a lossless 8-bit grey PNG, a mask as 0 and 255 so
that any viewer shows it black and white, labels in 8-bit grey up to 255
and in 16-bit grey up to 65,535; rows are y, as it is read. No pixel size,
origin or length unit is written (a warning says what is dropped): a flow
step's place on the half-pixel grid, for one, is not kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .registry import (
    HOLD_4D,
    LabelVolume,
    RawVolume,
    check_alpha,
    check_shape,
    colours_refused,
    import_library,
    note,
    placement_lost,
    reading,
    refuse_empty,
)

#: Pillow's modes read as they are (their integer type)
GREY = {"1": np.bool_, "L": np.uint8, "P": np.uint8, "I;16": np.uint16, "I;16B": np.uint16, "I;16L": np.uint16,
        "I": np.int32}
#: modes of grey stored as colour: the channels that must be equal
COLOUR = {"RGB": 3, "RGBA": 3, "LA": 1}
#: modes with an alpha channel, their last
ALPHA = ("RGBA", "LA")


def read(path: Path, dataset: str | None = None) -> RawVolume:
    pil = import_library("PIL.Image", "PNG", "pillow")
    where = str(path)
    with reading(path, "PNG"), pil.open(path) as image:
        if getattr(image, "n_frames", 1) > 1:
            raise IsoflowError(f"{where}: an animated PNG of {image.n_frames} frames; isoflow reads one image")
        mode = image.mode
        if mode not in GREY and mode not in COLOUR:
            raise IsoflowError(f"{where}: a PNG of mode {mode}, which isoflow does not read as labels")
        if mode in COLOUR and wide_channels(image):
            raise IsoflowError(f"{where}: a PNG of 16-bit colour or grey and alpha, whose channels Pillow reads as "
                               "8 bits (the labels would be wrong); save it as a 16-bit grey PNG")
        check_shape((image.width, image.height), GREY.get(mode, np.uint8), where)  # x first, as it is read
        data = np.asarray(image)
    if mode in COLOUR:
        channels = data[..., :COLOUR[mode]]
        grey = channels[..., 0]
        if not (channels == grey[..., None]).all():
            raise colours_refused(where, mode, "a grey (8- or 16-bit) or palette PNG")
        if mode in ALPHA:
            check_alpha(grey, data[..., -1], where, f"PNG mode {mode}", _alpha_as_grey(where))
        data = grey
    data = np.asarray(data, dtype=GREY.get(mode, np.uint8))
    return RawVolume(np.ascontiguousarray(data.T), np.ones(2))


def check(path: Path, obj: DigitalObject | LabelVolume, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    """Refuse what a PNG cannot hold of ``obj`` (a 3D object, no pixels a
    side; labels past 16 bits are refused by the format's ``max_label``)
    and say what it drops (the pixel size, origin and length unit), before
    anything is written.

    Parameters
    ----------
    path : pathlib.Path
        The PNG to be written, named in the messages.
    obj : DigitalObject or LabelVolume
        The image.
    dataset : str, optional
        Unused: a PNG holds one image.
    unit : str, optional
        The length unit of its pixel size and origin, said as dropped.
    space : str, optional
        The anatomical frame of its world axes, said as dropped.

    Raises
    ------
    IsoflowError
        One line naming ``path``.

    Examples
    --------
    >>> check(Path("stack.png"), DigitalObject(np.ones((2, 2, 2), bool)))
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: stack.png: a PNG holds a 2D image, this object is 3D; write .tif, .nii.gz, .nrrd, \
.h5 or .npz, which hold 3D
    """
    if obj.ndim != 2:
        # a TIFF holds no 4D object: it is named for a 3D one only
        elsewhere = HOLD_4D if obj.ndim == 4 else "write .tif, .nii.gz, .nrrd, .h5 or .npz, which hold 3D"
        raise IsoflowError(f"{path}: a PNG holds a 2D image, this object is {obj.ndim}D; {elsewhere}")
    refuse_empty(path, obj.volume.shape, "PNG")
    lost = placement_lost(obj, unit, space)  # said where what is read back differs
    if lost:
        note(f"{path}: PNG keeps no pixel size, origin or unit; {' and '.join(lost)} "
             f"{'are' if len(lost) > 1 else 'is'} not written (read back as pixel size 1, origin 0)")


def write(path: Path, obj: DigitalObject | LabelVolume, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    """Write the 2D ``obj`` that :func:`check` let through as a lossless
    grey PNG: a mask as 8-bit 0 and 255, labels as 8- or 16-bit grey
    (their own type), row ``j``, column ``i`` holding pixel ``(i, j)``.

    Parameters
    ----------
    path : pathlib.Path
        The file written (a temporary name beside the output: the format
        is named, not taken from the suffix).
    obj : DigitalObject or LabelVolume
        The image: a mask, or labels in uint8 or uint16.
    dataset, name, unit : optional
        Unused: a PNG holds one image and no place.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> path = Path(tempfile.mkdtemp()) / "l.png"
    >>> write(path, DigitalObject(np.array([[True, True], [False, True]])))
    >>> np.asarray(Image.open(path)).tolist()  # rows are y: pixel (0, 1) is row 1, column 0
    [[255, 0], [255, 255]]
    """
    pil = import_library("PIL.Image", "PNG", "pillow")
    rows = obj.volume.T  # row j, column i is pixel (i, j), as read() reads it
    if rows.dtype == np.bool_:
        rows = rows.view(np.uint8) * np.uint8(255)  # black and white in any viewer; read back as one mask
    # labels read from a big-endian file (NRRD, HDF5, ``>u2``) keep their byte order, which Pillow takes
    # for no grey mode: the same values in the machine's order
    rows = rows.astype(rows.dtype.newbyteorder("="), copy=False)
    if rows.dtype not in (np.uint8, np.uint16):  # write_labels narrows labels to the format's 16 bits first
        raise IsoflowError(f"{path}: a PNG holds 8- or 16-bit grey, and this image is {rows.dtype}")
    # Pillow takes uint8 as mode L and uint16 as I;16: grey of the labels' own width
    pil.fromarray(np.ascontiguousarray(rows)).save(path, format="PNG")


def _alpha_as_grey(where: str) -> str:
    """The command that saves the alpha of the PNG ``where`` as a grey PNG
    beside it (``NAME_alpha.png``)."""
    import json
    import shlex

    saved = str(Path(where).with_name(Path(where).stem + "_alpha.png"))
    code = f'from PIL import Image; Image.open({json.dumps(where)}).getchannel("A").save({json.dumps(saved)})'
    return f"python -c {shlex.quote(code)}"


def wide_channels(image) -> bool:
    """Whether a PNG Pillow opened stores 16 bits a channel in a mode of 8
    (``RGB``, ``RGBA``: Pillow keeps the high byte of each channel).

    Examples
    --------
    >>> import io
    >>> from PIL import Image
    >>> buffer = io.BytesIO()
    >>> Image.new("RGB", (2, 2)).save(buffer, format="PNG")
    >>> wide_channels(Image.open(buffer))
    False
    """
    # the decoder's raw mode, e.g. 'RGB;16B', says the depth the mode hides
    return any(";16" in str(tile[3]) for tile in image.tile)
