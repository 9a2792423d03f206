"""Reflectance spectra of texture texels: the spectra of a coarse lattice of RGB colours, between which each
texel's colour is interpolated in the kernels (`kernels.surfaces.rgb_reflectance`).

Each lattice node (RGB_LATTICE nodes per axis, 0 … 1) holds the spectrum a constant Base Color of its colour
gets (`spectra.scaled_from_rgb`, Jakob & Hanika 2019), so a texel of a node's colour renders exactly as that
constant colour. A colour between nodes takes a weighted sum of the 4 nodes of the tetrahedron it lies in
(Freudenthal's split of each cell into 6 tetrahedra around the cell's grey diagonal), with the weights that
give back its RGB: a colour's XYZ is linear in its spectrum, so each texel's colour under D65 is its own RGB's
(to the fit's precision), every spectrum is a convex sum of reflectances in [0, 1], and a grey texel
interpolates between two greys only, which are flat. Between nodes the spectrum's shape differs a little from
the fit of the texel's own colour (a metamer of it), which other illuminants than D65 can show.
"""

from functools import lru_cache

import numpy as np

from .kernels.layout import RGB_LATTICE
from .spectra import scaled_from_rgb
from .wavelengths import GRID


@lru_cache(maxsize=1)
def lattice_spectra() -> np.ndarray:
    """(RGB_LATTICE³, GRID) the nodes' reflectance spectra, node (i, j, k) of colour (i, j, k) / (RGB_LATTICE − 1)
    at row (i · RGB_LATTICE + j) · RGB_LATTICE + k (about 5 ms of fitting per node, once per process)."""
    levels = np.linspace(0.0, 1.0, RGB_LATTICE)
    table = np.empty((RGB_LATTICE**3, GRID.size))
    for row, (r, g, b) in enumerate(np.stack(np.meshgrid(levels, levels, levels, indexing="ij"), -1).reshape(-1, 3)):
        table[row] = np.clip(scaled_from_rgb((r, g, b)).values, 0.0, 1.0)
    table.flags.writeable = False
    return table
