"""Import Spectral Scene (File ▸ Import): a tracer scene folder opened as a Blender scene exports back to
the same scene (spectra drawn as curves within Blender's curve table; those no curve holds exactly);
bad files and unwritable data folders import nothing."""

import numpy as np
import pytest

from addon.export.scene import export_scene
from addon.tracer import spectra
from addon.tracer.scene import BlackbodyEmission, Camera, Fluorescence, Light, Medium
from addon.tracer.scene_io import save_scene
from tests.support.scene_compare import assert_same_scene
from tests.support.scenes import box_grid, scene, smooth_ramp

bpy = pytest.importorskip("bpy")


def _rotated_camera() -> Camera:
    matrix = np.eye(4)
    matrix[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]  # looks along +y
    matrix[:3, 3] = (0.5, -6.0, 0.3)
    return Camera(to_world=matrix, width=24, height=32, fov=np.radians(35.0), sensor_fit="VERTICAL",
                  shift_x=0.05, shift_y=-0.1)


def _every_feature():
    """One of everything the importer makes: a glowing medium with an albedo over density, a fluorescent
    one whose extinction (up to 4) no curve holds, a sun, a point, a spot and a sky."""
    glowing = box_grid((6, 5, 4), (1.2, 1.0, 0.8), (-0.8, 0.0, 0.0))
    temperature = box_grid((6, 5, 4), (1.2, 1.0, 0.8), (-0.8, 0.0, 0.0), density=2.0)
    temperature.values[0] = 1.0
    fire = Medium(name="Fire", density=glowing, density_scale=3.0, extinction=smooth_ramp(0.9, 0.2),
                  albedo_densities=np.array([0.0, 0.5]),
                  albedo_table=np.stack([smooth_ramp(0.8, 0.3).values, smooth_ramp(0.2, 0.6).values]),
                  anisotropy=spectra.constant(0.3), emission=BlackbodyEmission(temperature, 0.5, 900.0, 300.0))
    dye = Medium(name="Dye", density=box_grid((4, 4, 4), (1.0, 1.0, 1.0), (0.9, 0.0, 0.0)), density_scale=0.5,
                 extinction=smooth_ramp(4.0, 1.0), albedo_densities=np.array([0.0]),
                 albedo_table=spectra.constant(0.7).values[None, :], anisotropy=smooth_ramp(-0.2, 0.6),
                 phase="hg", fluorescence=Fluorescence(spectra.gaussian(440.0, 30.0, 1.5),
                                                       spectra.gaussian(560.0, 25.0), 0.8))
    lights = [
        Light(kind="sun", spectrum=spectra.blackbody(5500.0), strength=2.5, direction=np.array([0.6, 0.0, 0.8]),
              angle=np.radians(3.0), name="Sun"),
        Light(kind="point", spectrum=spectra.blackbody(3000.0), strength=4.0, position=np.array([1.0, 2.0, 3.0]),
              name="Bulb"),
        Light(kind="spot", spectrum=smooth_ramp(0.2, 1.0), strength=7.0, position=np.array([-2.0, 1.0, 2.0]),
              spot_direction=np.array([0.6, -0.3, -0.74]) / np.linalg.norm([0.6, -0.3, -0.74]),
              spot_size=np.radians(50.0), spot_blend=0.3, name="Spot"),
        Light(kind="area", spectrum=spectra.blackbody(4000.0), strength=60.0, position=np.array([0.5, -1.0, 2.5]),
              area_axes=_tilted_axes(), area_shape="ellipse", size_x=0.8, size_y=0.5, name="Panel", unit="radiant",
              camera_visible=True),
        Light(kind="sky", spectrum=spectra.blackbody(12000.0), strength=0.4,
              horizon_spectrum=smooth_ramp(1.0, 0.4), name="Sky"),
    ]
    return scene(_rotated_camera(), [fire, dye], lights, spp=7, seed=11, max_depth=9, bands=2,
                 wavelength_sampling="uv", wavelengths_per_path=1, lambda_min=300.0, lambda_max=780.0,
                 cmf="wyman3", backend="numpy")


def _tilted_axes():
    """An orthonormal frame turned 30° about X and 20° about Z (columns: local X, Y, Z)."""
    a, b = np.radians(30.0), np.radians(20.0)
    about_x = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    about_z = np.array([[np.cos(b), -np.sin(b), 0], [np.sin(b), np.cos(b), 0], [0, 0, 1]])
    return about_z @ about_x


def test_export_of_the_imported_scene_is_the_scene(registered, tmp_path):
    original = _every_feature()
    path = save_scene(original, tmp_path / "scene folder")
    assert bpy.ops.spectral.import_scene(filepath=str(path)) == {"FINISHED"}
    imported = bpy.context.scene
    assert imported.name == "scene folder" and imported.render.engine == "SPECTRAL_VOLUME"
    exported = export_scene(bpy.context.evaluated_depsgraph_get()).scene
    assert_same_scene(exported, original, curve=True, light_curves=True)
    dye = bpy.data.materials["Dye"].spectral
    assert dye.extinction.source == dye.excitation.source == "CSV"  # above the curves' range: exact
    np.testing.assert_allclose(next(m for m in exported.media if m.name == "Dye").extinction.values,
                               original.media[1].extinction.values, rtol=1e-12)
    assert sorted(p.name for p in (tmp_path / "scene folder" / "blender_data").iterdir()) == [
        "Dye.vdb", "Dye_excitation.csv", "Dye_extinction.csv", "Fire.vdb"]


def test_import_is_in_the_file_import_menu(registered):
    from addon.operators.import_scene import menu_entry

    assert menu_entry in bpy.types.TOPBAR_MT_file_import._dyn_ui_initialize()


def test_a_bad_scene_file_imports_nothing(registered, tmp_path):
    (tmp_path / "scene.json").write_text('{"format": "spectral-volume-scene", "version": 1}')
    scenes = len(bpy.data.scenes)
    with pytest.raises(RuntimeError, match=r"Nothing imported: scene: missing required field 'camera'"):
        bpy.ops.spectral.import_scene(filepath=str(tmp_path / "scene.json"))
    assert len(bpy.data.scenes) == scenes and sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


def test_an_unwritable_data_folder_imports_nothing(registered, tmp_path):
    path = save_scene(_every_feature(), tmp_path / "scene")
    (tmp_path / "file").write_text("not a folder")
    before = {name: len(getattr(bpy.data, name)) for name in ("scenes", "objects", "materials", "lights", "worlds")}
    with pytest.raises(RuntimeError, match=r"Nothing imported: cannot write .*file.*is a file, not a folder"):
        bpy.ops.spectral.import_scene(filepath=str(path), data_folder=str(tmp_path / "file" / "data"))
    assert before == {name: len(getattr(bpy.data, name)) for name in before}


def test_the_chosen_folder_imports_its_scene_json(registered, tmp_path):
    path = save_scene(_every_feature(), tmp_path / "clouds")
    assert bpy.ops.spectral.import_scene(filepath=str(path.parent)) == {"FINISHED"}
    assert bpy.context.scene.name == "clouds" and (tmp_path / "clouds" / "blender_data" / "Fire.vdb").is_file()


def test_a_scene_files_adaptive_sampling_is_imported(registered, tmp_path):
    """The importer sets Noise Threshold and Min Samples from the file: off where the file has none."""
    import dataclasses

    from addon.importer.parts import new_scene
    from addon.tracer.scene import RenderSettings

    fixed = new_scene("Fixed", 8, 8, RenderSettings())
    assert not fixed.spectral.use_adaptive_sampling
    adaptive = new_scene("Adaptive", 8, 8, dataclasses.replace(RenderSettings(), noise_threshold=0.05, min_samples=8))
    assert adaptive.spectral.use_adaptive_sampling and adaptive.spectral.adaptive_threshold == pytest.approx(0.05)
    assert adaptive.spectral.adaptive_min_samples == 8


def test_a_scene_files_firefly_filter_is_imported(registered):
    """Off where the file has none (its default, unbiased), on at the file's threshold where it has one."""
    import dataclasses

    from addon.importer.parts import new_scene
    from addon.tracer.scene import RenderSettings

    assert not new_scene("Unfiltered", 8, 8, RenderSettings()).spectral.use_firefly_filter
    filtered = new_scene("Filtered", 8, 8, dataclasses.replace(RenderSettings(), firefly_threshold=3.5)).spectral
    assert filtered.use_firefly_filter and filtered.firefly_threshold == pytest.approx(3.5)


def test_a_scene_files_film_transparent_is_imported(registered):
    import dataclasses

    from addon.importer.parts import new_scene
    from addon.tracer.scene import RenderSettings

    assert not new_scene("Opaque", 8, 8, RenderSettings()).render.film_transparent
    assert new_scene("Clear", 8, 8, dataclasses.replace(RenderSettings(), transparent=True)).render.film_transparent


def test_a_scene_files_backend_is_imported_as_device_and_backend(registered):
    """A file rendered on the GPU imports as Device ▸ GPU Compute (and exports as it came); a CPU backend as
    Device ▸ CPU with that backend."""
    import dataclasses

    from addon.export.scene import render_settings
    from addon.importer.parts import new_scene
    from addon.props.render import GPU_BACKEND
    from addon.tracer.scene import RenderSettings

    gpu = new_scene("Gpu", 8, 8, dataclasses.replace(RenderSettings(), backend=GPU_BACKEND))
    assert gpu.spectral.device == "GPU" and render_settings(gpu).backend == GPU_BACKEND
    oracle = new_scene("Oracle", 8, 8, dataclasses.replace(RenderSettings(), backend="numpy"))
    assert (oracle.spectral.device, oracle.spectral.backend) == ("CPU", "numpy")
    assert render_settings(oracle).backend == "numpy"
