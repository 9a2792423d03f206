"""Random numbers of paths: every path draws numbers 0, 1, 2, … of a stream keyed by (seed, band, pixel,
sample), and the i-th number depends on nothing else, so any split of the work over passes, tiles, threads
or machines draws exactly the same numbers for the same path.

The first `LOW_DISCREPANCY_DIMENSIONS` numbers of a path (its wavelengths, the position in the pixel, the
first free flights and light samples) are a low-discrepancy sequence over the pixel's samples: an
Owen-scrambled Sobol sequence, as in Burley, "Practical Hash-based Owen Scrambling" (JCGT 2020). The
dimensions come in groups of four that use Sobol dimensions 0–3; each group shuffles the sample index with
its own nested uniform scramble (so groups are decorrelated, and the first 2^k samples of a pixel still
form a scrambled (t, k, 4)-net in every group), and each dimension is scrambled by its own seed. Every
number is uniform on [0, 1), so estimates stay unbiased; the samples of a pixel are stratified, which
lowers the noise. Later numbers come from a counter-based hash (SplitMix64's finaliser).

Plain functions of uint64 arithmetic, exact on every CPU, shared by both backends (`shared_math`): they
work on scalars and on NumPy arrays alike.
"""

import numpy as np

from ..shared_math import shared

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MUL1 = np.uint64(0xBF58476D1CE4E5B9)
_MUL2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_UNIT = 1.0 / 9007199254740992.0  # 2⁻⁵³
_UNIT32 = 1.0 / 4294967296.0  # 2⁻³²
_LOW32 = np.uint64(0xFFFFFFFF)
_S1, _S2, _S4, _S8, _S16, _S24, _S32 = (np.uint64(s) for s in (1, 2, 4, 8, 16, 24, 32))
_ODD1, _ODD2, _ODD4, _ODD8 = (np.uint64(m) for m in (0x55555555, 0x33333333, 0x0F0F0F0F, 0x00FF00FF))
# Even multipliers of the hash-based nested uniform scramble (Burley 2020, after Laine and Karras):
# bit k of the result depends only on bits 0..k of the input, which makes the scramble nested.
_SCRAMBLE = tuple(np.uint64(m) for m in (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6))
_ONE = np.uint64(1)

LOW_DISCREPANCY_DIMENSIONS = 8
SOBOL_BITS = 32
GROUP = np.uint64(4)  # dimensions per group: Sobol dimensions 0-3


def _direction_numbers(degree: int, coefficients: int, initial: list[int]) -> list[int]:
    """The 32 direction numbers (as 32-bit integers) of a Sobol dimension with primitive polynomial of
    `degree` and inner `coefficients` (bits, highest first) and initial values m₁…m_degree."""
    v = []
    for k in range(SOBOL_BITS):
        if k < degree:
            v.append(initial[k] << (SOBOL_BITS - 1 - k))
            continue
        value = v[k - degree] ^ (v[k - degree] >> degree)
        for j in range(1, degree):
            if (coefficients >> (degree - 1 - j)) & 1:
                value ^= v[k - j]
        v.append(value)
    return v


# Generator matrices of Sobol dimensions 0-3 (columns as integers): van der Corput, then the primitive
# polynomials x + 1, x² + x + 1 and x³ + x + 1 with Joe and Kuo's initial values (1), (1, 3), (1, 3, 1).
SOBOL_MATRICES = np.array([[1 << (SOBOL_BITS - 1 - k) for k in range(SOBOL_BITS)],
                           _direction_numbers(1, 0, [1]),
                           _direction_numbers(2, 1, [1, 3]),
                           _direction_numbers(3, 1, [1, 3, 1])], dtype=np.uint64)


def _byte_tables(matrices: np.ndarray) -> np.ndarray:
    """SOBOL_BYTES[dimension, k, b]: the product of a generator matrix with byte k of an index equal to b
    (the XOR of the columns of b's set bits), so that a point takes four look-ups instead of 32 steps."""
    tables = np.zeros((matrices.shape[0], 4, 256), dtype=np.uint64)
    for value in range(256):
        for bit in range(8):
            if value >> bit & 1:
                for k in range(4):
                    tables[:, k, value] ^= matrices[:, 8 * k + bit]
    return tables


SOBOL_BYTES = _byte_tables(SOBOL_MATRICES)
_BYTE = np.uint64(0xFF)


@shared
def mix64(z):
    """SplitMix64's finaliser: a bijective 64-bit hash."""
    z = (z ^ (z >> _S30)) * _MUL1
    z = (z ^ (z >> _S27)) * _MUL2
    return z ^ (z >> _S31)


@shared
def pixel_key(seed, band, pixel):
    """The key of one pixel's samples (all arguments non-negative integers)."""
    key = mix64(np.uint64(seed) * _GOLDEN + np.uint64(band))
    return mix64(key ^ (np.uint64(pixel) * _MUL1))


@shared
def path_key(pixel, sample):
    """The stream key of one path: sample `sample` of the pixel whose key is `pixel`."""
    return mix64(pixel ^ (np.uint64(sample) * _MUL2))


@shared
def uniform(key, counter):
    """The `counter`-th hashed number of stream `key`, uniform in [0, 1)."""
    return (mix64(key + (np.uint64(counter) + _ONE) * _GOLDEN) >> _S11) * _UNIT


@shared
def reverse_bits32(x):
    """The low 32 bits of x in reverse order."""
    x = ((x >> _S1) & _ODD1) | ((x & _ODD1) << _S1)
    x = ((x >> _S2) & _ODD2) | ((x & _ODD2) << _S2)
    x = ((x >> _S4) & _ODD4) | ((x & _ODD4) << _S4)
    x = ((x >> _S8) & _ODD8) | ((x & _ODD8) << _S8)
    return ((x >> _S16) | (x << _S16)) & _LOW32


@shared
def nested_scramble(x, seed):
    """A nested uniform (Owen) scramble of the 32-bit fraction x, chosen by the 32-bit `seed`: a hash of
    the reversed bits in which each bit depends only on the bits above it in x."""
    x = (reverse_bits32(x) + seed) & _LOW32
    x ^= (x * _SCRAMBLE[0]) & _LOW32
    x ^= (x * _SCRAMBLE[1]) & _LOW32
    x ^= (x * _SCRAMBLE[2]) & _LOW32
    x ^= (x * _SCRAMBLE[3]) & _LOW32
    return reverse_bits32(x)


@shared
def sobol(index, dimension):
    """Point `index` (< 2³²) of Sobol dimension `dimension` (0-3) as a 32-bit fraction."""
    table = SOBOL_BYTES  # named once: CUDA code holds a copy of a global array per reference to it
    return (table[dimension, 0, index & _BYTE] ^ table[dimension, 1, (index >> _S8) & _BYTE]
            ^ table[dimension, 2, (index >> _S16) & _BYTE] ^ table[dimension, 3, (index >> _S24) & _BYTE])


@shared
def low_discrepancy(pixel, sample, counter):
    """The `counter`-th number (counter < LOW_DISCREPANCY_DIMENSIONS) of sample `sample` of the pixel with
    key `pixel`, uniform in [0, 1): Owen-scrambled Sobol over the pixel's samples (module docstring)."""
    group, component = counter // GROUP, counter % GROUP
    group_key = mix64(pixel + (np.uint64(group) + _ONE) * _GOLDEN)
    index = nested_scramble(np.uint64(sample) & _LOW32, group_key & _LOW32)
    seed = mix64(group_key + (np.uint64(component) + _ONE) * _MUL1) >> _S32
    return nested_scramble(sobol(index, component), seed) * _UNIT32
