"""How much spectral and RGB transport differ on a coloured medium, measured by a second engine: Mitsuba 3
renders the same homogeneous cube in its `scalar_rgb` and `scalar_spectral` variants, and the difference of
the two images' means is the allowance a spectral renderer may differ from an RGB one (Cycles) by.

The scene is the cube of a Blender scene (`[-1, 1]³`, a homogeneous medium of σ_t = density, albedo the RGB
colour, Henyey–Greenstein g) under white point lights (intensity P / (4π) for Blender's Power P), seen by
the scene's camera; the integrator is `volpath` to the same depth. Each variant is a subprocess
(Mitsuba's variant is process-wide)."""

import json
import subprocess
import sys

import numpy as np

from addon.tracer.lowering import camera_extent

_RENDER = r"""
import json, sys
import numpy as np
import mitsuba as mi
spec = json.loads(sys.argv[1])
mi.set_variant(spec["variant"])
scene = {
    "type": "scene",
    "integrator": {"type": "volpath", "max_depth": spec["depth"] + 1},
    "sensor": {"type": "perspective", "fov_axis": "x", "fov": spec["fov"],
               "to_world": mi.ScalarTransform4f(spec["to_world"]),
               "film": {"type": "hdrfilm", "width": spec["width"], "height": spec["height"],
                        "pixel_format": "rgb", "rfilter": {"type": "box"}},
               "sampler": {"type": "independent", "sample_count": spec["spp"]}},
    "medium": {"type": "homogeneous", "sigma_t": spec["density"], "albedo": {"type": "rgb", "value": spec["albedo"]},
               "phase": {"type": "hg", "g": spec["g"]}},
    "cube": {"type": "cube", "bsdf": {"type": "null"}, "interior": {"type": "ref", "id": "medium"}},
}
for index, (position, intensity) in enumerate(spec["lights"]):
    scene[f"light_{index}"] = {"type": "point", "position": position,
                               "intensity": {"type": "rgb", "value": [intensity] * 3}}
image = np.array(mi.render(mi.load_dict(scene), seed=spec["seed"]))
print(json.dumps(image.reshape(-1, image.shape[-1])[:, :3].mean(axis=0).tolist()))
"""

BLENDER_TO_MITSUBA_CAMERA = np.diag([-1.0, 1.0, -1.0, 1.0])


def _mean_rgb(spec: dict, variant: str) -> np.ndarray:
    done = subprocess.run([sys.executable, "-c", _RENDER, json.dumps({**spec, "variant": variant})],
                          capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise RuntimeError(f"Mitsuba ({variant}) failed: {done.stderr[-2000:]}")
    return np.array(json.loads(done.stdout.strip().splitlines()[-1]))


def spectral_vs_rgb(tracer_scene, lights, albedo, density: float, g: float, spp: int = 256):
    """(Mitsuba's RGB image mean, its spectral image mean) for the cube seen by `tracer_scene`'s camera
    (and its depth) holding a homogeneous medium of RGB `albedo`, lit by `lights`: (position, intensity
    in W/sr) of white point lights."""
    camera = tracer_scene.camera
    spec = {"depth": tracer_scene.settings.max_depth, "width": camera.width, "height": camera.height, "spp": spp,
            "fov": float(np.degrees(2.0 * np.arctan(0.5 * camera_extent(camera)[0]))),
            "to_world": (np.asarray(camera.to_world) @ BLENDER_TO_MITSUBA_CAMERA).tolist(),
            "density": density, "albedo": list(albedo), "g": g, "seed": 1,
            "lights": [(list(position), float(intensity)) for position, intensity in lights]}
    return _mean_rgb(spec, "scalar_rgb"), _mean_rgb(spec, "scalar_spectral")
