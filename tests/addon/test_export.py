"""Export: Blender scene → tracer Scene (grids, transforms, spectra, camera, lights) and its errors."""

import math

import numpy as np
import pytest

from addon.export import camera as camera_export
from addon.export.lights import point_intensity
from addon.export.scene import export_scene
from addon.tracer import grids, spectra
from addon.tracer.lowering import camera_extent
from addon.tracer.errors import SpectralError
from addon.tracer.scene import Grid
from addon.tracer.scene_io import load_scene
from tests.addon.builders import (PATTERN, add_camera, add_fluid_domain, add_sun, basic_scene, geometry_nodes, link,
                                  spectral_material, vdb_index_to_world, write_vdb)

bpy = pytest.importorskip("bpy")


def _export():
    return export_scene(bpy.context.evaluated_depsgraph_get())


def test_vdb_volume_grid_transform_and_spectra(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    cloud.location = (1.0, 2.0, 3.0)
    cloud.rotation_euler = (0.0, 0.0, math.radians(90))
    cloud.scale = (2.0, 2.0, 2.0)
    settings = cloud.material_slots[0].material.spectral
    settings.albedo.source = "COLOR"
    settings.albedo.color = (0.9, 0.5, 0.2)
    level = settings.albedo_levels.add()
    level.density = 0.5
    level.spectrum.value = 0.3
    settings.anisotropy.value = 0.4
    (medium,) = _export().scene.media
    np.testing.assert_array_equal(medium.density.values, PATTERN)
    expected = np.array(cloud.matrix_world) @ vdb_index_to_world()
    np.testing.assert_allclose(medium.density.index_to_world, expected, atol=1e-6)
    assert medium.name == "Cloud" and medium.density_scale == 4.0
    np.testing.assert_allclose(medium.albedo_densities, [0.0, 0.5])
    np.testing.assert_allclose(medium.albedo_table[0], spectra.from_rgb(tuple(settings.albedo.color)).values)
    np.testing.assert_allclose(medium.albedo_table[1], 0.3)
    np.testing.assert_allclose(medium.anisotropy.values, 0.4)
    assert medium.fluorescence is None and medium.emission is None


def test_vdb_sequence_follows_the_frame(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    for frame in (1, 2, 3):
        write_vdb(tmp_path / f"seq_{frame:04d}.vdb", scale=frame)
    cloud.data.filepath = str(tmp_path / "seq_0001.vdb")
    cloud.data.is_sequence = True
    cloud.data.frame_duration = 3
    scene.frame_set(3)
    np.testing.assert_allclose(_export().scene.media[0].density.values, PATTERN * 3)
    scene.frame_set(9)
    with pytest.raises(SpectralError, match=r"Volume 'Cloud': its sequence .*seq_0001.vdb has no file for frame 9"):
        _export()


def test_fluorescence_and_blackbody_from_the_temperature_grid(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    cloud.data.filepath = str(write_vdb(tmp_path / "fire.vdb", temperature=True))
    settings = cloud.material_slots[0].material.spectral
    settings.use_fluorescence = settings.use_blackbody = True
    settings.excitation.band = "UV365"
    settings.emission.peak, settings.emission.width = 520.0, 25.0
    settings.quantum_yield = 0.6
    settings.temperature_scale, settings.temperature_offset = 2.0, 300.0
    (medium,) = _export().scene.media
    np.testing.assert_allclose(medium.fluorescence.excitation.values, spectra.gaussian(365.0, 6.0).values)
    np.testing.assert_allclose(medium.fluorescence.emission.values, spectra.gaussian(520.0, 25.0).values)
    assert medium.fluorescence.quantum_yield == pytest.approx(0.6)
    np.testing.assert_allclose(medium.emission.temperature.values, PATTERN * 1000.0)
    assert (medium.emission.temperature_scale, medium.emission.temperature_offset) == (2.0, 300.0)


def test_evaluated_volume_with_mesh_to_volume_modifier(registered, tmp_path):
    scene = bpy.context.scene
    add_camera()
    add_sun()
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.5, 0.0, 0.25))
    cube = bpy.context.active_object
    cube.hide_render = True
    volume = link(bpy.data.objects.new("FromMesh", bpy.data.volumes.new("FromMesh")))
    volume.data.materials.append(spectral_material())
    volume.location = (0.0, 0.0, 1.0)
    modifier = volume.modifiers.new("ToVolume", "MESH_TO_VOLUME")
    modifier.object = cube
    modifier.resolution_mode, modifier.voxel_size = "VOXEL_SIZE", 0.1
    media = [m for m in _export().scene.media if m.name == "FromMesh"]
    assert len(media) == 1, "the cube itself is not spectral, only the volume made from it"
    grid = media[0].density
    assert grid.values.max() == pytest.approx(1.0)
    centres = np.argwhere(grid.values >= 0.5)  # the modifier's density falls to 0.5 at the surface
    world = (grid.index_to_world @ np.c_[centres, np.ones(len(centres))].T).T[:, :3]
    np.testing.assert_allclose(world.min(axis=0), [0.0, -0.5, -0.25], atol=0.16)  # the cube, in world space
    np.testing.assert_allclose(world.max(axis=0), [1.0, 0.5, 0.75], atol=0.16)


def test_geometry_nodes_mesh_to_volume_is_an_instance_at_its_matrix(registered):
    add_camera()
    add_sun()
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(2.0, 0.0, 0.5))
    cube = bpy.context.active_object
    cube.data.materials.append(spectral_material())
    node = geometry_nodes(cube, "GeometryNodeMeshToVolume")
    node.inputs["Resolution Mode"].default_value = "Size"
    node.inputs["Voxel Size"].default_value = 0.1
    (medium,) = _export().scene.media  # the volume only: the nodes leave the mesh empty
    assert medium.name == "Cube"
    centres = np.argwhere(medium.density.values >= 0.5)
    world = (medium.density.index_to_world @ np.c_[centres, np.ones(len(centres))].T).T[:, :3]
    np.testing.assert_allclose(world.min(axis=0), [1.5, -0.5, 0.0], atol=0.16)  # the cube, in world space
    np.testing.assert_allclose(world.max(axis=0), [2.5, 0.5, 1.0], atol=0.16)


def test_instanced_volumes_each_at_their_instance_matrix(registered, tmp_path):
    _scene, cloud = basic_scene(tmp_path)
    cloud.location = (0.0, 0.0, 1.0)
    group = bpy.data.collections.new("Clouds")
    group.objects.link(cloud)
    bpy.context.scene.collection.objects.unlink(cloud)
    for x in (-2.0, 3.0):
        holder = link(bpy.data.objects.new(f"Holder {x}", None))
        holder.instance_type, holder.instance_collection, holder.location = "COLLECTION", group, (x, 0.0, 0.0)
    media = _export().scene.media
    assert len(media) == 2
    origins = sorted(medium.density.index_to_world[0, 3] for medium in media)
    np.testing.assert_allclose(origins, [-2.0 + vdb_index_to_world()[0, 3], 3.0 + vdb_index_to_world()[0, 3]])


def test_particles_instance_volumes(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    emitter = bpy.context.active_object
    emitter.modifiers.new("Particles", "PARTICLE_SYSTEM")
    settings = emitter.particle_systems[0].settings
    settings.count, settings.frame_start, settings.frame_end, settings.lifetime = 5, 1, 1, 100
    settings.physics_type, settings.render_type, settings.instance_object = "NO", "OBJECT", cloud
    scene.frame_set(2)
    media = _export().scene.media
    assert len(media) == 6  # the cloud and its five instances, each at its place
    assert len({tuple(medium.density.index_to_world[:3, 3].round(6)) for medium in media}) == 6


def test_geometry_nodes_volume_uses_the_object_material_slot(registered, tmp_path):
    _scene, cloud = basic_scene(tmp_path)
    geometry_nodes(cloud, "GeometryNodeVolumeCube")  # a new volume: its output has no material
    (medium,) = _export().scene.media
    assert medium.density_scale == 4.0  # the material of the object's slot
    assert medium.density.values.max() == pytest.approx(1.0)  # the cube's density, not the file's


def test_mesh_with_spectral_material_is_voxelised(registered):
    add_camera()
    add_sun()
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.5))
    cube = bpy.context.active_object
    cube.data.materials.append(spectral_material())
    cube.spectral.voxel_size = 0.1
    (medium,) = _export().scene.media
    grid = medium.density
    assert grid.values.sum() == pytest.approx(1000, rel=0.02)
    inside = np.argwhere(grid.values > 0)
    world = (grid.index_to_world @ np.c_[inside, np.ones(len(inside))].T).T[:, :3]
    np.testing.assert_allclose(world.min(axis=0), [-0.45, -0.45, 0.05], atol=1e-6)
    np.testing.assert_allclose(world.max(axis=0), [0.45, 0.45, 0.95], atol=1e-6)


def test_voxelising_ignores_float32_rounding_of_the_mesh(registered):
    """A unit cube with vertices at x = 0.35 and 1.35 spans 1.0000000x in float32: still 16 voxels of
    1/16, centred in it."""
    add_camera()
    add_sun()
    mesh = bpy.data.meshes.new("Cube")
    corners = [(x, y, z) for x in (0.35, 1.35) for y in (-0.5, 0.5) for z in (0.0, 1.0)]
    mesh.from_pydata(corners, [], [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])
    cube = link(bpy.data.objects.new("Cube", mesh))
    cube.data.materials.append(spectral_material())
    cube.spectral.voxel_size = 1.0 / 16.0
    grid = _export().scene.media[0].density
    assert grid.values.shape == (18, 18, 18) and grid.values.sum() == 16**3
    np.testing.assert_allclose(grid.index_to_world[:3, 3], [0.85 - 17 / 32, -17 / 32, 0.5 - 17 / 32], atol=1e-6)


def test_fluid_domain_reads_its_openvdb_cache(registered, tmp_path):
    add_camera()
    add_sun()
    domain, density = add_fluid_domain(tmp_path, frames=(1, 2))
    material = domain.material_slots[0].material.spectral
    material.use_blackbody = True
    material.temperature_grid = "heat"
    bpy.context.scene.frame_set(2)
    (medium,) = _export().scene.media
    np.testing.assert_allclose(medium.density.values, density * 2)
    np.testing.assert_allclose(medium.emission.temperature.values, density * 2)
    # Cell (0, 0, 0) is centred half a cell inside the domain's lowest corner; cells are 0.25 wide.
    matrix = medium.density.index_to_world
    np.testing.assert_allclose(matrix @ [0, 0, 0, 1], [-2.0 + 0.125, -1.0 + 0.125, 0.0 + 0.125, 1.0], atol=1e-6)
    np.testing.assert_allclose(matrix @ [15, 7, 7, 1], [2.0 - 0.125, 1.0 - 0.125, 2.0 - 0.125, 1.0], atol=1e-6)
    material.temperature_grid = "flame"
    np.testing.assert_allclose(_export().scene.media[0].emission.temperature.values, density / 2)


def test_fluid_domain_without_a_cache_frame_is_reported(registered, tmp_path):
    add_camera()
    add_sun()
    add_fluid_domain(tmp_path)
    bpy.context.scene.frame_set(5)
    with pytest.raises(SpectralError, match=r"'Smoke Domain': no baked cache for frame 5: .*fluid_data_0005.vdb"):
        _export()


def test_camera_conventions(registered):
    scene = bpy.context.scene
    camera = add_camera(location=(1.0, 2.0, 3.0))
    camera.scale = (3.0, 3.0, 3.0)
    data = camera.data
    data.lens, data.sensor_width, data.sensor_height, data.sensor_fit = 50.0, 36.0, 24.0, "VERTICAL"
    data.shift_x, data.shift_y = 0.1, -0.2
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 400, 300, 50
    bpy.context.view_layer.update()
    exported = camera_export.export_camera(scene)
    assert (exported.width, exported.height) == (200, 150)
    assert exported.fov == pytest.approx(2 * math.atan(12.0 / 50.0))
    assert exported.sensor_fit == "VERTICAL" and (exported.shift_x, exported.shift_y) == pytest.approx((0.1, -0.2))
    np.testing.assert_allclose(exported.to_world[:3, :3] @ [0, 0, -1], [0, 1, 0], atol=1e-6)  # looks along +Y
    np.testing.assert_allclose(exported.to_world[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(np.linalg.norm(exported.to_world[:3, :3], axis=0), 1.0)  # scale dropped
    assert exported.to_world.flags.c_contiguous  # as the tracer's own cameras: one kernel specialisation
    data.type, data.ortho_scale = "ORTHO", 7.0
    exported = camera_export.export_camera(scene)
    assert exported.kind == "orthographic" and exported.ortho_scale == 7.0
    data.type = "PANO"
    with pytest.raises(SpectralError, match="panoramic cameras are not supported|pano cameras are not supported"):
        camera_export.export_camera(scene)


def _film_point(camera, px, py):
    """Camera-space film position (at z = -1 for perspective) of pixel corner (px, py), counted from the
    lower left."""
    extent_x, extent_y, offset_x, offset_y = camera_extent(camera)
    return np.array([(px / camera.width - 0.5) * extent_x + offset_x, (py / camera.height - 0.5) * extent_y + offset_y])


CAMERA_CASES = [(kind, fit, size) for kind in ("PERSP", "ORTHO") for fit in ("AUTO", "HORIZONTAL", "VERTICAL")
                for size in ((40, 30), (30, 40))]
# Pixel aspects x:y: square, and non-square ones that keep or swap the frame's larger axis (AUTO's fit).
PIXEL_ASPECTS = ((1.0, 1.0), (2.0, 1.0), (1.0, 1.7), (1.0, 1.2))


@pytest.mark.parametrize("pixel_aspect", PIXEL_ASPECTS, ids=lambda aspect: f"{aspect[0]:g}:{aspect[1]:g}")
@pytest.mark.parametrize("kind, fit, size", CAMERA_CASES)
def test_camera_frame_matches_blender_view_frame(registered, kind, fit, size, pixel_aspect):
    scene = bpy.context.scene
    data = add_camera().data
    data.type, data.sensor_fit, data.lens, data.ortho_scale = kind, fit, 35.0, 5.0
    data.sensor_width, data.sensor_height, data.shift_x, data.shift_y = 36.0, 20.0, 0.1, -0.05
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.pixel_aspect_x, scene.render.pixel_aspect_y = pixel_aspect
    exported = camera_export.export_camera(scene)
    corners = np.array([corner[:] for corner in data.view_frame(scene=scene)])
    if kind == "PERSP":
        corners = corners[:, :2] / -corners[:, 2:]
    low, high = _film_point(exported, 0, 0), _film_point(exported, exported.width, exported.height)
    np.testing.assert_allclose(corners[:, :2].min(axis=0), low, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(corners[:, :2].max(axis=0), high, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("kind, fit, size", CAMERA_CASES)
def test_render_region_camera_sees_the_region_of_the_frame(registered, kind, fit, size):
    scene = bpy.context.scene
    data = add_camera().data
    data.type, data.sensor_fit, data.shift_x, data.shift_y = kind, fit, 0.1, -0.05
    render = scene.render
    render.resolution_x, render.resolution_y = size
    full = camera_export.export_camera(scene)
    render.use_border = True
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.33, 0.77, 0.1, 0.55
    region = camera_export.render_region(scene)
    width, height = size
    assert (region.x, region.y) == (int(np.float32(0.33) * width), int(np.float32(0.1) * height))
    assert (region.x + region.width, region.y + region.height) == (int(np.float32(0.77) * width),
                                                                    int(np.float32(0.55) * height))
    part = camera_export.export_camera(scene)
    assert (part.width, part.height) == (region.width, region.height)
    np.testing.assert_allclose(_film_point(part, 0, 0), _film_point(full, region.x, region.y), atol=1e-9)
    np.testing.assert_allclose(_film_point(part, part.width, part.height),
                               _film_point(full, region.x + region.width, region.y + region.height), atol=1e-9)


def test_unit_scale_makes_materials_per_metre(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    assert _export().scene.media[0].density_scale == pytest.approx(4.0)
    scene.unit_settings.scale_length = 0.01  # a Blender unit is a centimetre: 1/100 of the optical depth
    assert _export().scene.media[0].density_scale == pytest.approx(0.04)


def test_settings_the_tracer_cannot_follow_are_warned(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    assert _export().warnings == []
    scene.render.pixel_aspect_x = 2.0  # followed (test_camera_frame_matches_blender_view_frame)
    assert _export().warnings == []
    scene.render.use_motion_blur = True
    warnings = _export().warnings
    assert len(warnings) == 1
    assert warnings[0].startswith("motion blur is not supported")


def test_lights_and_world(registered, tmp_path):
    """With their Spectral Light and Spectral World on, lights and the World render their spectra."""
    basic_scene(tmp_path)
    sun = bpy.data.objects["Sun"]
    sun.rotation_euler = (math.radians(45), 0.0, 0.0)
    sun.data.spectral.enabled = True
    sun.data.spectral.spectrum.source = "ILLUMINANT"
    point = link(bpy.data.objects.new("Bulb", bpy.data.lights.new("Bulb", "POINT")))
    point.location, point.data.energy = (1.0, 2.0, 3.0), 100.0
    point.data.spectral.enabled = True
    point.data.spectral.spectrum.source = "BLACKBODY"
    point.data.spectral.spectrum.temperature = 2700.0
    spot = link(bpy.data.objects.new("Spot", bpy.data.lights.new("Spot", "SPOT")))
    spot.data.spot_size, spot.data.spot_blend = math.radians(30), 0.3
    spot.data.spectral.enabled = True
    panel = link(bpy.data.objects.new("Panel", bpy.data.lights.new("Panel", "AREA")))
    panel.data.shape, panel.data.size, panel.data.size_y = "RECTANGLE", 2.0, 0.5
    panel.scale = (1.5, 1.0, 1.0)
    panel.data.spectral.enabled = True
    panel.visible_camera = True
    hidden = link(bpy.data.objects.new("Hidden", bpy.data.lights.new("Hidden", "AREA")))  # Blender's default: off
    hidden.data.spectral.enabled = True
    bpy.context.scene.world = bpy.data.worlds.new("Sky")
    bpy.context.scene.world.spectral.enabled = True
    bpy.context.scene.world.spectral.kind = "sky"
    bpy.context.scene.world.spectral.strength = 0.5
    result = _export()
    lights = {light.name: light for light in result.scene.lights}
    assert set(lights) == {"Sun", "Bulb", "Spot", "Panel", "Hidden", "Sky"}
    assert result.warnings == []
    panel = lights["Panel"]
    assert (panel.area_shape, panel.size_x, panel.size_y) == ("rectangle", pytest.approx(3.0), pytest.approx(0.5))
    assert panel.camera_visible is True and lights["Hidden"].camera_visible is False  # Ray Visibility ▸ Camera
    np.testing.assert_allclose(panel.area_axes, np.eye(3), atol=1e-6)
    # Blender's sun shines along its −Z; ours points towards the sun (+Z), tilted by the 45° X rotation.
    np.testing.assert_allclose(lights["Sun"].direction, [0.0, -math.sqrt(0.5), math.sqrt(0.5)], atol=1e-6)
    assert lights["Sun"].strength == 3.0
    np.testing.assert_allclose(lights["Sun"].spectrum.values, spectra.illuminant("D65").values)
    assert lights["Bulb"].strength == pytest.approx(100.0 / (4 * math.pi)) == pytest.approx(point_intensity(100.0))
    np.testing.assert_allclose(lights["Bulb"].position, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(lights["Bulb"].spectrum.values, spectra.blackbody(2700.0).values)
    np.testing.assert_allclose(lights["Spot"].spot_direction, [0.0, 0.0, -1.0], atol=1e-6)
    assert lights["Spot"].spot_size == pytest.approx(math.radians(30))
    assert lights["Spot"].spot_blend == pytest.approx(0.3)
    assert lights["Sky"].kind == "sky" and lights["Sky"].strength == 0.5 and lights["Sky"].horizon_spectrum is not None
    assert {light.unit for light in lights.values()} == {"luminous"}  # the default


def test_light_and_world_units_are_exported(registered, tmp_path):
    """A UV lamp's Power in watts: Radiant makes the tracer's intensity P / (4π) W/sr over its spectrum."""
    basic_scene(tmp_path)
    lamp = link(bpy.data.objects.new("UV lamp", bpy.data.lights.new("UV lamp", "POINT")))
    lamp.data.spectral.enabled = True
    lamp.data.energy, lamp.data.spectral.unit = 20.0, "radiant"
    bpy.context.scene.world = bpy.data.worlds.new("UV world")
    bpy.context.scene.world.spectral.enabled = True
    bpy.context.scene.world.spectral.unit = "radiant"
    bpy.data.objects["Sun"].data.spectral.enabled = True
    lights = {light.name: light for light in _export().scene.lights}
    assert lights["UV lamp"].unit == "radiant" and lights["UV world"].unit == "radiant"
    assert lights["Sun"].unit == "luminous"
    assert lights["UV lamp"].strength == pytest.approx(20.0 / (4 * math.pi))


def test_missing_vdb_file_is_named(registered, tmp_path):
    basic_scene(tmp_path)
    bpy.data.objects["Cloud"].data.filepath = str(tmp_path / "gone.vdb")
    with pytest.raises(SpectralError, match=r"Volume 'Cloud': VDB file .*gone.vdb does not exist"):
        _export()


def test_missing_grid_lists_the_grids(registered, tmp_path):
    _scene, cloud = basic_scene(tmp_path)
    cloud.spectral.density_grid = "smoke"
    with pytest.raises(SpectralError, match=r"Volume 'Cloud': .*'smoke'.*density"):
        _export()


def test_no_camera_is_reported(registered, tmp_path):
    basic_scene(tmp_path)
    bpy.context.scene.camera = None
    with pytest.raises(SpectralError, match="has no camera"):
        _export()


def test_volume_without_a_volume_material_is_named(registered, tmp_path):
    """Its material (a new one: a Principled BSDF surface) has no volume shader: as in Cycles, the volume
    renders nothing, and the warning says so."""
    _scene, cloud = basic_scene(tmp_path)
    cloud.material_slots[0].material.spectral.enabled = False
    export = _export()
    assert export.scene.media == ()
    assert export.warnings == ["not rendered: 1 volume without a volume material (Cloud (Smoke))"]


def test_no_lights_is_reported(registered, tmp_path):
    basic_scene(tmp_path)
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    with pytest.raises(SpectralError, match="the scene has no lights"):
        _export()


def test_export_operator_writes_a_loadable_scene(registered, tmp_path):
    basic_scene(tmp_path)
    out = tmp_path / "exported" / "scene.json"
    assert bpy.ops.spectral.export_scene(filepath=str(out)) == {"FINISHED"}
    loaded = load_scene(out)
    np.testing.assert_allclose(loaded.media[0].density.values, PATTERN)
    assert (loaded.camera.width, loaded.camera.height, loaded.settings.spp) == (16, 12, 2)


def test_export_operator_writes_nothing_on_bad_input(registered, tmp_path):
    basic_scene(tmp_path)
    out = tmp_path / "exported" / "scene.json"
    out.parent.mkdir()
    out.write_text("previous export")
    bpy.data.objects["Cloud"].data.filepath = str(tmp_path / "gone.vdb")
    with pytest.raises(RuntimeError, match="Nothing exported: Volume 'Cloud': VDB file"):
        bpy.ops.spectral.export_scene(filepath=str(out))
    assert out.read_text() == "previous export" and sorted(p.name for p in out.parent.iterdir()) == ["scene.json"]
