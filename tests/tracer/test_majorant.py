"""Majorant and minorant grids bound the density field in every block.

The kernels read the density as the trilinear interpolation of the grid (`lookups.trilinear`, zero
outside); delta and ratio tracking are unbiased only if each block's majorant is at least that field
everywhere in the block, and residual ratio tracking only if its minorant is at most it.
"""

import numpy as np
import pytest

from addon.tracer import spectra
from addon.tracer.kernels.lookups import trilinear
from addon.tracer.lowering import compile_scene
from addon.tracer.majorant import GLOW_COLLISIONS, block_size_for, majorant_grid, minorant_grid
from addon.tracer.scene import Glow
from tests.support import scenes as s


@pytest.mark.parametrize("shape, block", [((10, 7, 5), 3), ((16, 16, 16), 2), ((5, 5, 5), 6), ((12, 9, 20), None)])
def test_block_bounds_hold_the_interpolated_density(shape, block):
    rng = np.random.default_rng(4)
    values = (rng.random(shape) + 0.5).astype(np.float32)  # no zeros inside: interior minorants are positive
    block = block or block_size_for(shape)
    upper, lower = majorant_grid(values, block), minorant_grid(values, block)
    assert upper.shape == lower.shape
    # Points in padded index space: every block, its corners and faces included.
    extent = np.array(upper.shape) * block
    points = rng.random((200_000, 3)) * extent
    points[:2000] = np.floor(points[:2000] / block) * block  # block corners
    blocks = np.minimum(np.floor(points / block).astype(int), np.array(upper.shape) - 1)
    data = values.ravel()
    field = trilinear(data, 0, np.array(shape), points[:, 0] - 1.0, points[:, 1] - 1.0, points[:, 2] - 1.0)
    high = upper[blocks[:, 0], blocks[:, 1], blocks[:, 2]]
    low = lower[blocks[:, 0], blocks[:, 1], blocks[:, 2]]
    assert np.all(field <= high * (1 + 1e-6))
    assert np.all(field >= low * (1 - 1e-6))
    # Exactly the blocks whose footprint (padded cells b·B … (b+1)·B) stays off the zero padding have a
    # positive minorant; the largest majorant is the largest sample.
    interior = [(np.arange(nb) > 0) & ((np.arange(nb) + 1) * block < n + 1) for nb, n in zip(upper.shape, shape)]
    expected = interior[0][:, None, None] & interior[1][None, :, None] & interior[2][None, None, :]
    np.testing.assert_array_equal(lower > 0.0, expected)
    assert upper.max() == values.max()


@pytest.mark.parametrize("extinction", [0.0, 0.1, 50.0])
def test_a_glow_raises_the_majorant_to_its_floor(extinction):
    """A glowing medium's majorant coefficient is at least GLOW_COLLISIONS per world diagonal at its largest
    density, and its extinction's where that is more; a medium without a glow keeps its extinction's."""
    box = s.box_grid(cells=(8, 8, 4), size=(4.0, 2.0, 1.0), density=2.0)  # diagonal √21
    plain = s.medium(box, 3.0, extinction=extinction)
    glowing = s.medium(box, 3.0, extinction=extinction, glow=Glow(spectrum=spectra.constant(1.0)))
    coeff = compile_scene(s.scene(s.ortho_camera(), [plain, glowing], [s.sun([0, 0, 1])])).majorant.coeff
    assert coeff[0] == 3.0 * extinction
    assert coeff[1] == pytest.approx(max(3.0 * extinction, GLOW_COLLISIONS / (np.sqrt(21.0) * 2.0)), rel=1e-12)
