"""Display images for people: a denoised view of each render and the captioned contact sheet.

Only pictures are made here; every figure the demos print is computed from the raw film (`metrics`),
and the EXR keeps the raw film with its variance. Volumes at a few dozen samples per pixel are
grainy, so the display image goes through the add-on's denoiser (Intel Open Image Denoise, guided by
the film's variance: addon/tracer/denoise.py), as F12 with Denoise on does.
"""

import numpy as np

from addon.tracer import colorimetry, denoise, image_io


def display_rgb(xyz: np.ndarray, variance: np.ndarray | None = None) -> np.ndarray:
    """Linear Rec.709 of the film; denoised when its `variance` (of the XYZ estimate) is given."""
    rgb = colorimetry.xyz_to_rgb(xyz)
    return rgb if variance is None else denoise.denoise(rgb, variance)


# ----------------------------------------------------------------------------- contact sheet

GAP, HEADER, CAPTION_LINE = 8, 30, 15


def _wrap(text: str, width: int, size: int = 12) -> list[str]:
    """`text` broken at spaces into lines no wider than `width` pixels at font `size`."""
    import OpenImageIO as oiio

    lines = [""]
    for word in text.split():
        candidate = f"{lines[-1]} {word}".strip()
        if lines[-1] and oiio.ImageBufAlgo.text_size(candidate, size).width > width:
            lines.append(word)
        else:
            lines[-1] = candidate
    return lines


def contact_sheet(path, tiles, title: str, columns: int = 4) -> bool:
    """Write a PNG of `tiles` [(linear Rec.709 image, exposure already applied, [caption lines])] in a
    grid under `title`, through the Standard view like every demo PNG. Returns whether the captions
    could be drawn (OpenImageIO draws text with a font it ships; if that fails, the captions are only
    in the text file written beside the sheet)."""
    import OpenImageIO as oiio

    tile_h, tile_w = tiles[0][0].shape[:2]
    tiles = [(image, [wrapped for line in caption for wrapped in _wrap(line, tile_w)]) for image, caption in tiles]
    lines = max(len(caption) for _, caption in tiles)
    cell_h = tile_h + lines * CAPTION_LINE + 10
    rows = -(-len(tiles) // columns)
    width, height = columns * tile_w + (columns + 1) * GAP, HEADER + rows * (cell_h + GAP)
    sheet = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, "float"))
    oiio.ImageBufAlgo.fill(sheet, (0.006, 0.006, 0.007))
    drawn = oiio.ImageBufAlgo.render_text(sheet, GAP, 20, title, 16, "", (1.0, 1.0, 1.0))
    for index, (image, caption) in enumerate(tiles):
        x = GAP + (index % columns) * (tile_w + GAP)
        y = HEADER + (index // columns) * (cell_h + GAP)
        tile = oiio.ImageBuf(oiio.ImageSpec(tile_w, tile_h, 3, "float"))
        tile.set_pixels(oiio.ROI(), np.ascontiguousarray(np.clip(image[:tile_h, :tile_w], 0.0, 1.0), dtype=np.float32))
        oiio.ImageBufAlgo.paste(sheet, x, y, 0, 0, tile)
        for line, text in enumerate(caption):
            drawn &= oiio.ImageBufAlgo.render_text(sheet, x, y + tile_h + 14 + line * CAPTION_LINE, text, 12, "",
                                                   (0.9, 0.9, 0.9) if line == 0 else (0.5, 0.5, 0.5))
    image_io.write_png(path, sheet.get_pixels(oiio.FLOAT))
    return bool(drawn)
