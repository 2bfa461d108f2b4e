"""PNG: 2D masks and label images (Pillow), read only.

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
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import IsoflowError
from .registry import RawVolume, check_alpha, check_shape, colours_refused, import_library, reading

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
