"""Majorant and minorant grids: the maximum and the minimum density over coarse blocks of a density grid.

The density field is the trilinear interpolation of the cell-centre samples with zero outside the
array, so it is non-zero inside (-1, n) in index space. Kernels work in *padded* index space
(index + 1), where the field lives in (0, n + 1) and majorant block b along an axis spans
[b·B, (b+1)·B). A point in that block is influenced by the padded cells b·B … (b+1)·B (inclusive), and
its density is a convex combination of theirs, so the block's majorant and minorant are the maximum and
the minimum over those cells (the padding's zeros included; a block reaching past the array holds zero
density).

Free flights track against the majorant; shadow rays towards delta lights, and those of grey paths,
track the minorant's extinction analytically and only the residual against the majorant (residual ratio
tracking). A glowing medium's majorant coefficient has a floor (`glow_floor`): its emission is collected
at tentative collisions, which a medium that barely attenuates would otherwise hardly have.
"""

import numpy as np


# Tentative collisions a ray meets along a glowing medium's grid diagonal, at least, where the density is
# largest: each collects the glow (docs/algorithm.md).
GLOW_COLLISIONS = 8


def glow_floor(values: np.ndarray, diagonal: float) -> float:
    """The least majorant coefficient per unit raw density of a glowing medium whose grid holds `values` and
    has a world diagonal `diagonal` long: GLOW_COLLISIONS per diagonal at its largest density (0 if empty)."""
    peak = float(np.max(values))
    return GLOW_COLLISIONS / (diagonal * peak) if peak > 0 else 0.0


def block_size_for(shape, target_blocks: int = 16) -> int:
    """A block size giving about `target_blocks` blocks along the longest axis (at least 1 cell)."""
    return max(1, int(np.ceil((max(shape) + 1) / target_blocks)))


def _block_reduce(values: np.ndarray, block: int, reduce) -> np.ndarray:
    """`reduce` (np.maximum or np.minimum) of `values` over each block's footprint, float32."""
    padded = np.pad(np.asarray(values, dtype=np.float32), 1)  # padded cell p = cell p-1; zeros at borders
    n_blocks = [int(np.ceil((n + 1) / block)) for n in values.shape]
    reduced = padded
    for axis, nb in enumerate(n_blocks):
        size = reduced.shape[axis]
        parts = []  # a footprint clipped at the far end holds the padding's zero there
        for lo in np.arange(nb) * block:
            footprint = np.take(reduced, np.arange(lo, min(lo + block + 1, size)), axis=axis)
            parts.append(reduce.reduce(footprint, axis=axis, keepdims=True))
        reduced = np.concatenate(parts, axis=axis)
    return reduced.astype(np.float32)


def majorant_grid(values: np.ndarray, block: int) -> np.ndarray:
    """Maximum of `values` over each block's footprint (see module docstring), float32."""
    return _block_reduce(values, block, np.maximum)


def minorant_grid(values: np.ndarray, block: int) -> np.ndarray:
    """Minimum of `values` over each block's footprint (see module docstring), float32."""
    return _block_reduce(values, block, np.minimum)
