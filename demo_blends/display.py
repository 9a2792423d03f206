"""Display images for people: a denoised view of each render and the captioned contact sheet.

Only pictures are made here; every figure the demos print is computed from the raw film (`metrics`),
and the EXR keeps the raw film with its variance. Volumes at a few dozen samples per pixel are
grainy, so the display image is filtered with non-local means guided by the film's own variance
(Rousselle, Knaus & Zwicker 2012, "Adaptive rendering with non-local means filtering"): two pixels are
averaged when their patches differ by no more than their noise explains. Isolated fireflies are
first pulled down to their neighbourhood (display only).
"""

import numpy as np
from scipy.ndimage import median_filter, uniform_filter

from addon.tracer import colorimetry, image_io


def _tame_fireflies(xyz: np.ndarray, factor: float = 6.0) -> np.ndarray:
    """Scale down pixels whose Y exceeds `factor` × the median of their 5×5 neighbourhood (hue kept)."""
    luminance = xyz[..., 1]
    limit = factor * median_filter(luminance, size=5, mode="nearest") + 1e-6
    scale = np.where(luminance > limit, limit / np.maximum(luminance, 1e-12), 1.0)
    return xyz * scale[..., None]


def denoise(xyz: np.ndarray, variance: np.ndarray, radius: int = 5, patch: int = 2, k: float = 0.6) -> np.ndarray:
    """Non-local means on XYZ with the per-pixel variance of the estimate setting what counts as noise."""
    xyz = _tame_fireflies(xyz)
    height, width = xyz.shape[:2]
    pad = radius + patch
    u = np.pad(xyz, ((pad, pad), (pad, pad), (0, 0)), mode="reflect")
    v = np.pad(variance, ((pad, pad), (pad, pad), (0, 0)), mode="reflect")
    inner = (slice(radius, radius + height + 2 * patch), slice(radius, radius + width + 2 * patch))
    up, vp = u[inner], v[inner]
    total, weights = np.zeros_like(xyz), np.zeros((height, width, 1))
    crop = (slice(patch, patch + height), slice(patch, patch + width))
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            shifted = (slice(radius + dy, radius + dy + height + 2 * patch),
                       slice(radius + dx, radius + dx + width + 2 * patch))
            uq, vq = u[shifted], v[shifted]
            distance = ((up - uq) ** 2 - (vp + np.minimum(vp, vq))) / (1e-10 + k * k * (vp + vq))
            distance = uniform_filter(distance.mean(axis=2), size=2 * patch + 1)[crop]
            weight = np.exp(-np.maximum(distance, 0.0))[..., None]
            total += weight * uq[crop]
            weights += weight
    return total / weights


def display_rgb(xyz: np.ndarray, variance: np.ndarray | None = None) -> np.ndarray:
    """Linear Rec.709 of the (denoised, when `variance` is given) film."""
    return colorimetry.xyz_to_rgb(xyz if variance is None else denoise(xyz, variance))


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
