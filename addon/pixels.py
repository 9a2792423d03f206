"""Tracer film → Blender pixel buffers: rows flipped (Blender stores the bottom row first), flattened
per pixel, float32 for `foreach_set` and render passes."""

import numpy as np


def blender_rows(image: np.ndarray) -> np.ndarray:
    """(height, width, channels), top row first → (height · width, channels), bottom row first, float32."""
    height, width, channels = image.shape
    return np.ascontiguousarray(image[::-1].reshape(height * width, channels), dtype=np.float32)


def with_alpha(rgb: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """RGB → RGBA; `alpha` (height, width) defaults to 1 (a volume render covers the whole frame, its
    background included)."""
    alpha = np.ones(rgb.shape[:2]) if alpha is None else alpha
    return np.concatenate([rgb, alpha[..., None]], axis=2)
