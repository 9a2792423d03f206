"""The light passes beside the image, as Cycles makes them: Emission, Environment, Volume Direct and Volume Indirect.

The kernels split each camera path's light into categories (`kernels/light_split.py`: what the camera sees before
any vertex, the background a camera ray escapes to, the light arriving at the first vertex, the rest), and the film
sums each category's XYZ per pixel and band (`Film.sum_light`). A pass is its category's mean over the samples,
summed over bands, in linear Rec.709 as Combined. The identity:

    Emission + Environment + Volume Direct + Volume Indirect + (light whose first vertex is on a surface) = Combined

per pixel, within float error. The last term is Cycles' (DiffDir + DiffInd) × DiffCol; the engine makes no Diffuse
Color pass to divide it by, so Diffuse Direct and Indirect are not offered (the render's warning names them).
"""

import numpy as np

from . import colorimetry
from .kernels.light_split import CATEGORIES, EMISSION, ENVIRONMENT, VOLUME_DIRECT, VOLUME_INDIRECT

# Blender 5's names of the passes (its Render Result, EXR channels `ViewLayer.Emission.R`, …)
EMIT, ENV, VOLUME_DIR, VOLUME_IND = "Emission", "Environment", "Volume Direct", "Volume Indirect"
LIGHT_PASSES = {EMIT: EMISSION, ENV: ENVIRONMENT, VOLUME_DIR: VOLUME_DIRECT, VOLUME_IND: VOLUME_INDIRECT}  # slot


def light_categories(settings) -> int:
    """The light categories the film keeps for `settings`: all of them where it asks for a light pass, else 0."""
    return CATEGORIES if any(name in LIGHT_PASSES for name in settings.passes) else 0


def light_images(film, settings) -> dict:
    """The light passes `settings` asks for, by Blender name: (height, width, 3) linear Rec.709 each."""
    if not film.light_categories:
        return {}
    xyz = film.light_xyz
    return {name: colorimetry.xyz_to_rgb(xyz[..., slot, :]) for name, slot in LIGHT_PASSES.items()
            if name in settings.passes}


def light_rgb(film) -> np.ndarray:
    """Every light category of the film in linear Rec.709, (height, width, CATEGORIES, 3): they sum to Combined."""
    return colorimetry.xyz_to_rgb(film.light_xyz)
