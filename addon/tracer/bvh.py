"""A bounding volume hierarchy over triangles, built once per compile (`lowering`), in NumPy.

The triangles are sorted along a Morton curve of their centroids (21 bits per axis), and each node's range of
the sorted triangles splits where the highest bit that differs between its first and last codes changes
(Karras 2012): a spatial split, found for a whole level of nodes at once by one `searchsorted`. Where the
codes are all equal, or past MEDIAN_FROM_LEVEL levels, the range splits at its middle instead, so the tree's
depth stays within `layout.BVH_MAX_DEPTH` whatever the geometry. A node of at most LEAF_TRIANGLES triangles is a
leaf. Nodes are numbered level by level with each node's children side by side, as `KernelSurfaces` keeps
them; each node's box is the union of its triangles' boxes (one `reduceat` per level). A million triangles
build in a few seconds.
"""

import numpy as np

from .kernels.layout import BVH_MAX_DEPTH

LEAF_TRIANGLES = 4
MORTON_BITS = 21
MEDIAN_FROM_LEVEL = 48  # then median splits: at most log2(triangles) more levels, within BVH_MAX_DEPTH
assert MEDIAN_FROM_LEVEL + 40 < BVH_MAX_DEPTH  # 2⁴⁰ triangles is beyond any memory


def _spread_bits(q: np.ndarray) -> np.ndarray:
    """The 21 low bits of each of `q` (uint64) moved to every third bit (bit i to bit 3i)."""
    q = q & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        q = (q | (q << np.uint64(shift))) & np.uint64(mask)
    return q


def morton_codes(points: np.ndarray) -> np.ndarray:
    """Morton codes (uint64, 63 bits) of points (n, 3), quantised over their bounding box."""
    low, high = points.min(axis=0), points.max(axis=0)
    span = high - low
    scale = np.where(span > 0, (2**MORTON_BITS - 1) / np.where(span > 0, span, 1.0), 0.0)
    q = np.minimum((points - low) * scale, 2**MORTON_BITS - 1).astype(np.uint64)
    return _spread_bits(q[:, 0]) | (_spread_bits(q[:, 1]) << np.uint64(1)) | (_spread_bits(q[:, 2]) << np.uint64(2))


def _highest_bit(x: np.ndarray) -> np.ndarray:
    """The index of the highest set bit of each of `x` (uint64, non-zero)."""
    bit = np.floor(np.log2(x.astype(np.float64))).astype(np.int64)  # may be one too high where x rounds up
    bit = np.where((x >> bit.astype(np.uint64)) == 0, bit - 1, bit)
    return bit


def _splits(codes: np.ndarray, start: np.ndarray, end: np.ndarray, level: int) -> np.ndarray:
    """Where each range [start, end) of the sorted `codes` splits (start < split < end)."""
    middle = (start + end) // 2
    first, last = codes[start], codes[end - 1]
    differ = first != last
    if level >= MEDIAN_FROM_LEVEL or not differ.any():
        return middle
    bit = _highest_bit(np.where(differ, first ^ last, np.uint64(1))).astype(np.uint64)
    target = (last >> bit) << bit  # the least code with that bit set and the same bits above it
    split = np.searchsorted(codes, target, side="left")
    return np.where(differ, np.clip(split, start + 1, end - 1), middle)


def build(low: np.ndarray, high: np.ndarray):
    """The hierarchy over boxes (triangles' bounds) `low`, `high` (T, 3), T ≥ 1: (order, node_bounds,
    node_first, node_count), `order` being the triangles in the order the leaves index (see `KernelSurfaces`)."""
    codes = morton_codes(0.5 * (low + high))
    order = np.argsort(codes, kind="stable")
    codes = codes[order]
    low, high = low[order], high[order]
    starts, ends, firsts, counts = [], [], [], []
    start, end = np.array([0]), np.array([low.shape[0]])
    level, next_index = 0, 1
    while start.size:
        assert level < BVH_MAX_DEPTH
        size = end - start
        leaf = size <= LEAF_TRIANGLES
        inner = np.flatnonzero(~leaf)
        first = np.where(leaf, start, 0)
        first[inner] = next_index + 2 * np.arange(inner.size)
        starts.append(start)
        ends.append(end)
        firsts.append(first)
        counts.append(np.where(leaf, size, 0))
        split = _splits(codes, start[inner], end[inner], level)
        next_index += 2 * inner.size
        start = np.stack([start[inner], split], axis=1).ravel()
        end = np.stack([split, end[inner]], axis=1).ravel()
        level += 1
    bounds = [_range_bounds(low, high, s, e) for s, e in zip(starts, ends)]
    return order, np.concatenate(bounds), np.concatenate(firsts), np.concatenate(counts)


def _range_bounds(low: np.ndarray, high: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(nodes, 6): the union of the boxes of each range [start, end) (disjoint, increasing, non-empty)."""
    indices = np.stack([start, end], axis=1).ravel()
    padded_low = np.concatenate([low, low[:1]])
    padded_high = np.concatenate([high, high[:1]])
    lower = np.minimum.reduceat(padded_low, indices, axis=0)[::2]
    upper = np.maximum.reduceat(padded_high, indices, axis=0)[::2]
    return np.concatenate([lower, upper], axis=1)
