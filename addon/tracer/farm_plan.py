"""A farm render's plan: the units of work (one per wavelength band × pass × image tile) and `PassMerger`,
which adds their results to the film in pass order, so that the film's floating-point sums are formed
exactly as by `render.render` whatever order the units complete in (farm.py runs them on Dask).

The passes are the single-process render's (`render.pass_sizes`); the tiles are fixed squares (the
single-process render sizes its own from throughput instead: tiles do not change a pixel's sums).
"""

from dataclasses import dataclass

import numpy as np

from .errors import SpectralError
from .film import Film
from .render import pass_sizes


@dataclass(frozen=True)
class Unit:
    """One task: samples [begin, end) (pass `pass_index`) of `band` over tile `tile_index`."""

    band: int
    pass_index: int
    tile_index: int
    samples: tuple[int, int]
    tile: tuple[int, int, int, int]  # x0, y0, width, height

    @property
    def pixel_samples(self) -> int:
        return self.tile[2] * self.tile[3] * (self.samples[1] - self.samples[0])


def image_tiles(width: int, height: int, tile_size: int) -> list[tuple[int, int, int, int]]:
    """Tiles (x0, y0, width, height) covering the image row by row; edge tiles are smaller."""
    if tile_size < 1:
        raise SpectralError(f"tile size must be at least 1 pixel, got {tile_size}")
    return [(x0, y0, min(tile_size, width - x0), min(tile_size, height - y0))
            for y0 in range(0, height, tile_size) for x0 in range(0, width, tile_size)]


def plan(width: int, height: int, bands: int, spp: int, tile_size: int,
         group: int = 0) -> tuple[list[int], list, list[Unit]]:
    """(pass sizes, tiles, units): the single-process render's passes × bands × tiles, in pass order (with the
    firefly filter's `group`, as the single-process render then adds them: passes of one group of samples)."""
    sizes = [group] * (spp // group) if group else pass_sizes(spp)
    tiles = image_tiles(width, height, tile_size)
    units, begin = [], 0
    for pass_index, size in enumerate(sizes):
        for band in range(bands):
            for tile_index, tile in enumerate(tiles):
                units.append(Unit(band, pass_index, tile_index, (begin, begin + size), tile))
        begin += size
    return sizes, tiles, units


class PassMerger:
    """Adds unit results to a `Film` so that its sums are formed exactly as by `render.render`.

    The single-process render adds whole-image passes of each band in pass order. Pixels are
    independent, so adding a pass tile by tile gives the same per-pixel sums; what must be kept is
    the order of passes within a band. Results that arrive early are buffered until every tile of
    their pass has arrived and all earlier passes of their band have been added; the film's sample
    count of a band therefore always describes every pixel (previews are consistent)."""

    def __init__(self, film: Film, sizes: list[int], tiles: list[tuple[int, int, int, int]]):
        self.film, self.sizes, self.tiles = film, list(sizes), list(tiles)
        self.next_pass = [0] * film.bands
        self.waiting: dict[tuple[int, int], dict[int, tuple[np.ndarray, ...]]] = {}

    def add(self, unit: Unit, sum_xyz: np.ndarray, sum_sq: np.ndarray, sum_transparent: np.ndarray,
            sum_light: np.ndarray | None = None, sum_spectrum: np.ndarray | None = None, peaks=None) -> None:
        """Add a unit's accumulators (`render.render_unit`'s: the light categories' and the spectral bins' where
        the film has them, and the peaks where it keeps them)."""
        if unit.pass_index < self.next_pass[unit.band]:
            raise ValueError(f"pass {unit.pass_index} of band {unit.band} was already added")
        arrived = self.waiting.setdefault((unit.band, unit.pass_index), {})
        arrived[unit.tile_index] = (sum_xyz, sum_sq, sum_transparent, sum_light, sum_spectrum, peaks)
        band = unit.band
        while self.next_pass[band] < len(self.sizes):
            parts = self.waiting.get((band, self.next_pass[band]))
            if parts is None or len(parts) < len(self.tiles):
                break
            del self.waiting[(band, self.next_pass[band])]
            for tile_index in sorted(parts):
                x0, y0, _, _ = self.tiles[tile_index]
                xyz, squares, transparent, light, spectrum, peaks = parts[tile_index]
                self.film.add(band, y0, x0, xyz, squares, self.sizes[self.next_pass[band]], transparent, light,
                              spectrum, peaks)
            self.next_pass[band] += 1

    @property
    def complete(self) -> bool:
        return all(done == len(self.sizes) for done in self.next_pass)
