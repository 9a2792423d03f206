"""The data passes beside the image, as Cycles makes them: Depth, Mist, Normal, and Cryptomatte's Object and
Material mattes, from the first surface each camera ray meets (`kernels/first_hit.py`).

Per pixel, over its samples (the path tracer's camera rays, so the passes cover a pixel as the image does):
- Depth: the camera-space depth of sample 0's hit (Cycles writes it on the first sample only), 1e10 where
  that ray meets no surface (Cycles' value for the background).
- Mist: 1 − mean over the samples of (1 − m)·hit, m = clamp((distance − start) / depth, 0, 1) raised to the
  World ▸ Mist Pass falloff (quadratic: m², linear: m, inverse quadratic: √m): 0 at the start, 1 beyond
  start + depth and on the background.
- Normal: the mean world-space normal (on the side facing the camera), the background counting as 0.
- Cryptomatte: each pixel's objects (or materials) ranked by coverage (the fraction of its samples hitting
  them), `cryptomatte_depth` of them, two per RGBA pass (id, coverage, id, coverage) in CryptoObject00,
  CryptoObject01, …; an id is the name's MurmurHash3 (32 bits, seed 0) as a float32 (an exponent of all
  zeros or ones has its lowest bit flipped, as the Cryptomatte specification says), and `metadata` gives
  each matte's name, hash, conversion and manifest (name → hash in hex) under `cryptomatte/<key>/…`, <key>
  being the first 7 hex digits of the hash of the layer's name ("ViewLayer.CryptoObject").
Media do not write these passes, as in Cycles: rays pass through volumes to the surface behind (or the
background).
"""

import json
from typing import NamedTuple

import numpy as np

from . import checks
from .errors import SpectralError
from .kernels.layout import FIRST_HIT_VALUES, KernelScene
from .light_passes import LIGHT_PASSES

DEPTH, MIST, NORMAL, CRYPTO_OBJECT, CRYPTO_MATERIAL = "Depth", "Mist", "Normal", "CryptoObject", "CryptoMaterial"
DATA_PASSES = (DEPTH, MIST, NORMAL, CRYPTO_OBJECT, CRYPTO_MATERIAL)  # the names a scene may ask for
# each pass's channels: a Cryptomatte pass's are "RGBA", a light pass's (`light_passes`) "RGB"
CHANNELS = {DEPTH: "Z", MIST: "Z", NORMAL: "XYZ", **{name: "RGB" for name in LIGHT_PASSES}}
MIST_FALLOFFS = {"quadratic": 2.0, "linear": 1.0, "inverse_quadratic": 0.5}  # Blender's, as Cycles' exponents
NO_HIT_DEPTH = 1e10
CRYPTOMATTE_DEPTH_MAX = 16  # Blender's largest pass_cryptomatte_depth
FIRST_HIT_BYTES = 32 << 20  # the first hits held at once (per chunk of rows and samples)


class PassImages(NamedTuple):
    """The data passes of a render: each pass's pixels (height, width, channels) by its Blender name
    (CryptoObject00, …), and each Cryptomatte kind's names (its manifest)."""

    images: dict
    mattes: dict

    def metadata(self, layer: str = "ViewLayer") -> dict:
        """The EXR header entries of the Cryptomatte passes, in render layer `layer`."""
        entries = {}
        for kind, names in self.mattes.items():
            entries.update(cryptomatte_metadata(f"{layer}.{kind}", names))
        return entries


def murmurhash3_32(text: str, seed: int = 0) -> int:
    """MurmurHash3 (x86, 32 bits) of `text`'s UTF-8 bytes, as Cryptomatte hashes names."""
    data = text.encode("utf-8")
    c1, c2, mask = 0xCC9E2D51, 0x1B873593, 0xFFFFFFFF
    h = seed & mask
    whole = len(data) // 4 * 4
    for i in range(0, whole, 4):
        k = int.from_bytes(data[i:i + 4], "little")
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        h ^= (k * c2) & mask
        h = ((h << 13) | (h >> 19)) & mask
        h = (h * 5 + 0xE6546B64) & mask
    tail = data[whole:]
    if tail:
        k = int.from_bytes(tail, "little")
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        h ^= (k * c2) & mask
    h ^= len(data)
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & mask
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & mask
    return h ^ (h >> 16)


def hash_float(name: str) -> np.float32:
    """A Cryptomatte id: the name's hash as float32 bits, with an exponent of all zeros or all ones (a
    denormal, inf or NaN) made ordinary by flipping its lowest bit."""
    h = murmurhash3_32(name)
    exponent = (h >> 23) & 0xFF
    if exponent in (0, 255):
        h ^= 1 << 23
    return np.array([h], dtype=np.uint32).view(np.float32)[0]


def cryptomatte_metadata(layer_name: str, names) -> dict:
    """The EXR header entries of one Cryptomatte layer (`layer_name`, e.g. "ViewLayer.CryptoObject")."""
    key = f"cryptomatte/{murmurhash3_32(layer_name):08x}"[:19]
    manifest = {name: f"{murmurhash3_32(name):08x}" for name in sorted(set(names))}
    return {f"{key}/name": layer_name, f"{key}/hash": "MurmurHash3_32", f"{key}/conversion": "uint32_to_float32",
            f"{key}/manifest": json.dumps(manifest, separators=(",", ":"))}


def cryptomatte_passes(kind: str, depth: int) -> list[str]:
    """The Blender pass names of a Cryptomatte `kind` at `depth` levels: two levels per RGBA pass."""
    return [f"{kind}{i:02d}" for i in range((depth + 1) // 2)]


def pass_channels(settings) -> dict:
    """Every data and light pass `settings` asks for, by Blender name, with its channel letters (in order)."""
    channels = {}
    for name in settings.passes:
        if name in CHANNELS:
            channels[name] = CHANNELS[name]
        else:
            channels.update({each: "RGBA" for each in cryptomatte_passes(name, settings.cryptomatte_depth)})
    return channels


def matte_names(scene, kind: str) -> list[str]:
    """Each surface's Cryptomatte name: its object's (or material's) name, the surface's own name where the
    scene does not give one."""
    if kind == CRYPTO_OBJECT:
        return [surface.object or surface.name for surface in scene.surfaces]
    return [surface.material or surface.name for surface in scene.surfaces]


def render_passes(scene, kernel_scene: KernelScene, spp: int, seed: int, backend: str = "numba") -> PassImages:
    """The data passes `scene.settings.passes` asks for (module docstring), from spp first hits per pixel, in
    chunks of rows and samples of about FIRST_HIT_BYTES (Cryptomatte's per-name counts included)."""
    settings = scene.settings
    wanted = set(settings.passes) & set(DATA_PASSES)
    if not wanted:
        return PassImages({}, {})
    find = first_hit_function(backend)
    camera, surfaces = kernel_scene.camera, kernel_scene.surfaces
    width, height = camera.width, camera.height
    mattes = {kind: _matte_table(scene, kind) for kind in (CRYPTO_OBJECT, CRYPTO_MATERIAL) if kind in wanted}
    depth = np.full((height, width), NO_HIT_DEPTH)
    mist = np.zeros((height, width))
    normal = np.zeros((height, width, 3))
    levels = {kind: np.zeros((height, width, 2 * settings.cryptomatte_depth)) for kind in mattes}
    exponent = MIST_FALLOFFS[settings.mist_falloff]
    names = sum(len(ids) for ids, _ in mattes.values())
    samples = max(1, min(spp, FIRST_HIT_BYTES // (8 * FIRST_HIT_VALUES * width)))
    rows = max(1, FIRST_HIT_BYTES // (width * (8 * FIRST_HIT_VALUES * samples + 4 * names)))
    for y0 in range(0, height, rows):
        h = min(rows, height - y0)
        counts = {kind: np.zeros((h, width, len(ids)), np.int32) for kind, (ids, _) in mattes.items()}
        for begin in range(0, spp, samples):
            count = min(samples, spp - begin)
            values, triangles = np.empty((h, width, count, FIRST_HIT_VALUES)), np.empty((h, width, count), np.int64)
            find(camera, surfaces, np.int64(0), np.int64(y0), np.int64(width), np.int64(h), np.int64(begin),
                 np.int64(begin + count), np.uint64(seed), values, triangles)
            hit = triangles >= 0
            if begin == 0:
                depth[y0:y0 + h] = np.where(hit[..., 0], values[..., 0, 0], NO_HIT_DEPTH)
            m = np.clip((np.where(hit, values[..., 1], 0.0) - settings.mist_start) / settings.mist_depth, 0.0, 1.0)
            mist[y0:y0 + h] += ((1.0 - m**exponent) * hit).sum(axis=2)
            normal[y0:y0 + h] += values[..., 2:].sum(axis=2)
            owner = kernel_scene.surfaces.surface[np.maximum(triangles, 0)]
            for kind, (ids, of_surface) in mattes.items():
                _count(counts[kind], np.where(hit, of_surface[owner], -1), len(ids))
        for kind, (ids, _) in mattes.items():
            levels[kind][y0:y0 + h] = _ranked(counts[kind], ids, spp, settings.cryptomatte_depth)
    images = {}
    if DEPTH in wanted:
        images[DEPTH] = depth[..., None]
    if MIST in wanted:
        images[MIST] = (1.0 - mist / spp)[..., None]
    if NORMAL in wanted:
        images[NORMAL] = normal / spp
    for kind in mattes:
        images.update(_in_passes(kind, levels[kind]))
    return PassImages(images, {kind: ids for kind, (ids, _) in mattes.items()})


def first_hit_function(backend: str):
    """The first-hit kernel of a backend: the Numba kernel (the CUDA backend's too: the data passes' first hits
    run on the CPU), or the NumPy backend's oracle."""
    if backend in ("numba", "cuda"):
        from .kernels.first_hit import first_hits
    else:
        from .kernels.numpy_backend import first_hits
    return first_hits


def first_hit_ready(kernel_scene: KernelScene, cancel=None, notice=None) -> bool:
    """Compile the Numba first-hit kernel for the scene's argument types (or load it from the kernel cache),
    cancellably, telling `notice` as the path tracer's kernel does (`numba_cache.ready`); False if cancelled."""
    import numba

    from .kernels import first_hit, numba_cache

    one = np.int64(1)
    arguments = (kernel_scene.camera, kernel_scene.surfaces, one, one, one, one, one, one, np.uint64(0),
                 np.empty((1, 1, 1, FIRST_HIT_VALUES)), np.empty((1, 1, 1), np.int64))
    signature = tuple(numba.typeof(argument) for argument in arguments)
    return numba_cache.ready(first_hit.first_hits, lambda: first_hit.first_hits.compile(signature), cancel, notice)


def _matte_table(scene, kind: str) -> tuple[list[str], np.ndarray]:
    """The distinct matte names of a kind and each surface's index among them."""
    names = matte_names(scene, kind)
    distinct = sorted(set(names))
    return distinct, np.array([distinct.index(name) for name in names] or [0], np.int64)


def _count(counts: np.ndarray, matte: np.ndarray, mattes: int) -> None:
    """Add to `counts` (h, w, mattes) the samples of each matte in `matte` (h, w, samples; -1: none)."""
    h, w, _ = matte.shape
    pixel = np.arange(h * w).reshape(h, w, 1) * (mattes + 1)
    flat = np.bincount((pixel + matte + 1).ravel(), minlength=h * w * (mattes + 1))
    counts += flat.reshape(h, w, mattes + 1)[..., 1:].astype(np.int32)


def _ranked(counts: np.ndarray, names: list[str], spp: int, depth: int) -> np.ndarray:
    """Each pixel's `depth` names of most samples in `counts` (h, w, names), as (id, coverage) pairs: (h, w,
    2 depth), empty levels 0."""
    height, width, _ = counts.shape
    ids = np.array([hash_float(name) for name in names] + [0.0], np.float32)
    padded = np.concatenate((counts, np.zeros((height, width, depth), np.int32)), axis=2)
    order = np.argsort(-padded, axis=2, kind="stable")[..., :depth]  # ties: the lower index first
    coverage = np.take_along_axis(padded, order, axis=2) / spp
    matte_id = np.where(coverage > 0, ids[np.minimum(order, len(names))], 0.0)
    return np.stack((matte_id, coverage), axis=3).reshape(height, width, 2 * depth)


def _in_passes(kind: str, levels: np.ndarray) -> dict:
    """Cryptomatte levels (h, w, 2 depth) as the RGBA passes of a kind, two levels each (the last padded)."""
    height, width, pairs = levels.shape
    passes = cryptomatte_passes(kind, pairs // 2)
    levels = np.concatenate((levels, np.zeros((height, width, 4 * len(passes) - pairs))), axis=2)
    return {name: levels[..., 4 * i:4 * i + 4] for i, name in enumerate(passes)}


def check_passes(settings, where: str = "render") -> None:
    """The passes' part of `check_settings`: known names (data and light passes), a mist range, a Cryptomatte
    depth."""
    if not isinstance(settings.passes, (tuple, list)):
        raise SpectralError(f"{where}.passes: expected a list of pass names, found {checks.shown(settings.passes)}")
    known = (*DATA_PASSES, *LIGHT_PASSES)
    for i, name in enumerate(settings.passes):
        if name not in known:
            raise SpectralError(f"{where}.passes[{i}]: unknown pass {name!r}: choose from {', '.join(known)}")
    checks.number(settings.mist_start, f"{where}.mist_start")
    if checks.number(settings.mist_depth, f"{where}.mist_depth") <= 0:
        raise SpectralError(f"{where}.mist_depth: must be above 0, found {settings.mist_depth}")
    checks.one_of(settings.mist_falloff, f"{where}.mist_falloff", tuple(MIST_FALLOFFS))
    checks.whole_within(settings.cryptomatte_depth, f"{where}.cryptomatte_depth", 1, CRYPTOMATTE_DEPTH_MAX)
