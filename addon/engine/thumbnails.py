"""Material, light and World previews (the Properties editor's and the asset browser's thumbnails).

Blender renders them with the engine on its own preview scene (a sphere or other shape carrying the
material, a floor, two area lights and a preview World), exported as any scene, so a preview is lit as
Cycles lights it. A preview with no light of its own but the World is given a key light: a sun from the
camera's upper left, so that scattering shows as shading rather than vanishing into the uniform World (a
white scattering medium in a uniform environment is invisible). Previews render at the preview scene's
Viewport Samples (Blender's preview scene keeps the add-on's default settings, not the user's).
"""

import dataclasses

import numpy as np

from ..tracer import spectra
from ..tracer.scene import Light, Scene

KEY_LIGHT_STRENGTH = 3.0  # luminance of the key sun's irradiance; the preview World's radiance is 1
KEY_LIGHT_FROM = (-0.5, 0.7, 0.6)  # towards the key sun, in the camera's (right, up, back) axes


def preview_scene(scene: Scene, samples: int) -> Scene:
    """The exported preview scene as a preview renders it: with a key light if it has none of its own
    but the World, at `samples` per pixel, keeping no spectral image (a thumbnail writes no Spectral EXR)."""
    settings = dataclasses.replace(scene.settings, spp=samples, spectrum=False)
    if any(light.kind in ("sun", "point", "spot", "area") for light in scene.lights):
        return dataclasses.replace(scene, settings=settings)
    axes = np.asarray(scene.camera.to_world)[:3, :3]
    direction = axes @ np.asarray(KEY_LIGHT_FROM)
    key = Light(kind="sun", spectrum=spectra.illuminant("D65"), strength=KEY_LIGHT_STRENGTH,
                direction=direction / np.linalg.norm(direction), name="Preview key light")
    return dataclasses.replace(scene, lights=scene.lights + (key,), settings=settings)
