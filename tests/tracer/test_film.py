"""The film: per-pixel sample counts, so that a film holding part of a pass is a consistent image."""

import numpy as np

from addon.tracer.film import Film


def test_a_partly_added_pass_leaves_every_pixel_its_own_mean():
    rng = np.random.default_rng(3)
    film = Film(5, 4, bands=2)
    first, second = rng.random((2, 2, 4, 5, 3))
    for band in range(2):
        film.add(band, 0, 0, first[band] * 2, (first[band] ** 2) * 2, 2)  # a whole pass of 2 samples
    film.add(0, 1, 2, second[0, 1:3, 2:5] * 4, second[0, 1:3, 2:5] ** 2 * 4, 4)  # one tile of the next pass
    assert film.samples.tolist() == [2, 2]
    assert film.pixel_samples[0].sum() == 2 * 20 + 4 * 6 and film.pixel_samples[1].sum() == 2 * 20
    expected = first.sum(axis=0)
    expected[1:3, 2:5] += (second[0, 1:3, 2:5] * 4 - first[0, 1:3, 2:5] * 4) / 6  # (2·a + 4·b)/6 − a
    np.testing.assert_allclose(film.xyz, expected)
    np.testing.assert_allclose(film.mean_xyz, film.xyz.reshape(-1, 3).mean(axis=0))
    assert np.all(film.variance >= 0)


def test_an_empty_film_is_black_with_no_variance():
    film = Film(3, 2)
    assert film.samples.tolist() == [0]
    assert not film.xyz.any() and not film.variance.any() and not film.mean_xyz.any()


def test_variance_is_the_sample_variance_of_the_mean_summed_over_bands():
    rng = np.random.default_rng(5)
    values = rng.random((2, 7, 2, 3, 3))  # band, sample, rows, columns, XYZ
    film = Film(3, 2, bands=2)
    for band in range(2):
        for sample in values[band]:
            film.add(band, 0, 0, sample, sample**2, 1)
    expected = (values.var(axis=1, ddof=1) / 7).sum(axis=0)
    np.testing.assert_allclose(film.variance, expected, rtol=1e-12)
    one = Film(3, 2)
    one.add(0, 0, 0, values[0, 0], values[0, 0] ** 2, 1)
    assert not one.variance.any()  # one sample says nothing about the spread


def test_alpha_is_one_minus_the_mean_transparency_summed_over_bands():
    """Each band's mean transparency is its share of the background seen; alpha is 1 − their sum, per pixel
    by its own sample count, and 1 where no transparency was added."""
    film = Film(2, 1, bands=2)
    zeros = np.zeros((1, 2, 3))
    film.add(0, 0, 0, zeros, zeros, 4, np.array([[1.0, 2.0]]))  # transparency 0.25 and 0.5 in band 0
    film.add(1, 0, 0, zeros, zeros, 2, np.array([[0.5, 0.0]]))  # 0.25 and 0 in band 1
    np.testing.assert_allclose(film.alpha, [[0.5, 0.5]])
    film.add(0, 0, 1, zeros[:, :1], zeros[:, :1], 4)  # more samples of one pixel, seeing nothing
    np.testing.assert_allclose(film.alpha, [[0.5, 0.75]])
    np.testing.assert_allclose(Film(3, 2).alpha, 1.0)
