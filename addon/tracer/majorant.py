"""Majorant grids: the maximum density over coarse blocks of a density grid.

The density field is the trilinear interpolation of the cell-centre samples with zero outside the
array, so it is non-zero inside (-1, n) in index space. Kernels work in *padded* index space
(index + 1), where the field lives in (0, n + 1) and majorant block b along an axis spans
[b·B, (b+1)·B). A point in that block is influenced by the padded cells b·B … (b+1)·B (inclusive),
so the block's majorant is the maximum over those cells (clipped to the array).
"""

import numpy as np


def block_size_for(shape, target_blocks: int = 16) -> int:
    """A block size giving about `target_blocks` blocks along the longest axis (at least 1 cell)."""
    return max(1, int(np.ceil((max(shape) + 1) / target_blocks)))


def majorant_grid(values: np.ndarray, block: int) -> np.ndarray:
    """Maximum of `values` over each block's footprint (see module docstring), float32."""
    padded = np.pad(np.asarray(values, dtype=np.float32), 1)  # padded cell p = cell p-1; zeros at borders
    n_blocks = [int(np.ceil((n + 1) / block)) for n in values.shape]
    out = np.zeros(n_blocks, dtype=np.float32)
    starts = [np.arange(nb) * block for nb in n_blocks]
    # Per axis, the padded cells b·B … (b+1)·B of each block, clipped to the padded array.
    reduced = padded
    for axis, (nb, s) in enumerate(zip(n_blocks, starts)):
        size = reduced.shape[axis]
        parts = [np.take(reduced, np.arange(lo, min(lo + block + 1, size)), axis=axis).max(axis=axis, keepdims=True)
                 if lo < size else np.zeros_like(np.take(reduced, [0], axis=axis))
                 for lo in s]
        reduced = np.concatenate(parts, axis=axis)
    out[...] = reduced
    return out
