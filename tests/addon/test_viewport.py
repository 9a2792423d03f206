"""The Rendered viewport: its camera from the 3D view's matrices, the progressive schedule, restarts and
cancellation (`addon.engine.viewport_render`, with a stand-in renderer where no kernel is needed), and the
engine's `view_update` / `view_draw` on a Blender scene (Blender-as-a-module has no window: they are
called here with stand-ins for the engine and the 3D view; drawing goes to a `gpu` offscreen buffer)."""

import dataclasses
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest

from addon.jobs import tracer_job
from addon.engine.render_engine import SpectralVolumeEngine, region_camera
from addon.export.camera import export_camera
from addon.export.scene import export_scene
from addon.output import blender_rows, with_alpha
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from addon.tracer.lowering import camera_extent
from addon.tracer.render import RenderResult, render
from addon.tracer.scene import look_at
from addon.engine.viewport_render import (RESOLUTION_DIVISORS, Step, ViewportRenderer, filled, resized, schedule,
                                   view_camera, view_pixels)
from addon.tracer.fireflies import Peaks, as_finished, filtered
from tests.addon.builders import basic_scene, tiny_render
from tests.support import scenes

bpy = pytest.importorskip("bpy")


# ------------------------------------------------------------------------------ the pure logic


def test_schedule_refines_resolution_then_samples():
    assert RESOLUTION_DIVISORS == (8, 4, 2)
    assert schedule(512, 300, 64) == [Step(64, 38, 1), Step(128, 75, 1), Step(256, 150, 1), Step(512, 300, 64)]
    assert schedule(5, 3, 8) == [Step(1, 1, 1), Step(2, 1, 1), Step(3, 2, 1), Step(5, 3, 8)]
    assert schedule(2, 2, 8) == [Step(1, 1, 1), Step(2, 2, 8)]  # 1/8 and 1/4 round up to the same size
    assert schedule(1, 1, 3) == [Step(1, 1, 3)]


def test_a_resized_camera_sees_the_same_frame():
    camera = dataclasses.replace(scenes.perspective_camera(width=500, height=301), shift_x=0.1, shift_y=-0.2)
    for width, height in ((63, 38), (125, 76), (250, 151)):
        np.testing.assert_allclose(camera_extent(resized(camera, width, height)), camera_extent(camera), rtol=1e-12)


def _orthographic_matrix(left, right, bottom, top, near, far):
    """Blender's `orthographic_m4` (rows as mathutils prints them)."""
    return np.array([[2 / (right - left), 0, 0, -(right + left) / (right - left)],
                     [0, 2 / (top - bottom), 0, -(top + bottom) / (top - bottom)],
                     [0, 0, -2 / (far - near), -(far + near) / (far - near)],
                     [0, 0, 0, 1.0]])


def test_a_free_orthographic_view_sees_behind_its_origin():
    """Blender clips free orthographic views from −clip_end/2: the camera moves back there."""
    to_world = look_at((0.0, -10.0, 0.0), (0.0, 0.0, 0.0))
    window = _orthographic_matrix(-4.0, 4.0, -1.0, 2.0, -500.0, 500.0)
    camera = view_camera(np.linalg.inv(to_world), window, 80, 30)
    assert camera.kind == "orthographic" and camera.ortho_scale == pytest.approx(8.0)
    np.testing.assert_allclose(camera.to_world[:3, 3], (0.0, -510.0, 0.0), atol=1e-9)
    np.testing.assert_allclose(camera.to_world[:3, :3], to_world[:3, :3], atol=1e-12)
    extent = camera_extent(camera)
    np.testing.assert_allclose(extent, (8.0, 3.0, 0.0, 0.5), atol=1e-12)  # the frame's centre is 0.5 up


def test_view_pixels_scale_up_by_nearest_neighbour_bottom_row_first():
    film = Film(2, 2)
    film.add(0, 0, 0, np.arange(12, dtype=np.float64).reshape(2, 2, 3), np.zeros((2, 2, 3)), 1)
    low = blender_rows(with_alpha(film.rgb())).reshape(2, 2, 4)  # bottom row first
    pixels = view_pixels(film, 5, 4)
    assert pixels.shape == (4, 5, 4) and pixels.dtype == np.float32
    np.testing.assert_array_equal(pixels[:2, :3], np.broadcast_to(low[0, 0], (2, 3, 4)))
    np.testing.assert_array_equal(pixels[2:, 3:], np.broadcast_to(low[1, 1], (2, 2, 4)))
    np.testing.assert_array_equal(pixels[:, :, 3], 1.0)
    np.testing.assert_array_equal(view_pixels(film, 2, 2), low)


def test_the_full_views_first_pass_fills_the_previous_image():
    film = Film(3, 2)
    film.add(0, 0, 0, np.full((1, 3, 3), 2.0), np.zeros((1, 3, 3)), 1)  # the top row has its first sample
    behind = np.full((2, 3, 4), 0.5, dtype=np.float32)
    pixels = filled(view_pixels(film, 3, 2), film, behind)
    np.testing.assert_array_equal(pixels[1], view_pixels(_constant_film(3, 2, 2.0), 3, 2)[1])  # top row: rendered
    np.testing.assert_array_equal(pixels[0], behind[0])  # bottom row (first in the pixels): the previous image
    np.testing.assert_array_equal(filled(view_pixels(film, 3, 2), film, None), view_pixels(film, 3, 2))


def test_a_refining_image_is_shown_filtered_as_the_result_will_be():
    """With the firefly filter a film keeps peaks, and its progress images (the viewport's while it refines, F12's
    Render Result) show it filtered; without the filter the film is shown as it is."""
    rng = np.random.default_rng(6)
    film = Film(5, 5, group=1)
    for sample in range(8):
        xyz = rng.normal(1.0, 0.1, size=(5, 5, 3))
        if sample == 3:
            xyz[2, 2] = 40.0
        film.add(0, 0, 0, xyz, xyz**2, 1, None, None, None, Peaks.of(xyz, xyz**2, np.zeros((5, 5, 0, 3)),
                                                                      np.zeros((5, 5, 0))))
    settings = scenes.scene(scenes.perspective_camera(5, 5), firefly_threshold=2.0).settings
    shown = as_finished(film, settings.firefly_threshold)
    assert shown.xyz[2, 2, 1] < 3.0 < film.xyz[2, 2, 1]
    np.testing.assert_array_equal(shown.sum_xyz, filtered(film, 2.0).sum_xyz)
    plain = _constant_film(5, 5, 1.0)
    assert as_finished(plain, settings.firefly_threshold) is plain


class StandInRun:
    """Renders a Y = 1 film unit by unit (`unit` seconds each) until cancelled; records each call."""

    def __init__(self, unit=0.01, units=3, error=None):
        self.unit, self.units, self.error = unit, units, error
        self.calls, self.returned = [], []

    def __call__(self, scene, scheduler, *, spp, progress, cancel, notice, unit_seconds):
        camera = scene.camera
        self.calls.append((camera.width, camera.height, spp, scene))
        if self.error is not None:
            raise self.error
        film = Film(camera.width, camera.height)
        cancelled = False
        for unit in range(self.units):
            if cancel():
                cancelled = True
                break
            time.sleep(self.unit)
            if unit == self.units - 1:
                film.add(0, 0, 0, np.full((camera.height, camera.width, 3), float(spp)),
                         np.zeros((camera.height, camera.width, 3)), spp)
            progress(film, (unit + 1) / self.units)
        self.returned.append(time.perf_counter())
        return RenderResult(film=film, cancelled=cancelled)


def _tracer_scene(width=40, height=30, samples=4):
    return scenes.scene(scenes.perspective_camera(width, height), lights=[scenes.environment()], spp=samples)


def test_the_renderer_runs_the_schedule_and_shows_the_full_view():
    run = StandInRun()
    viewport = ViewportRenderer(run)
    scene = _tracer_scene()
    viewport.render(scene, "")
    assert viewport.wait(10) and not viewport.busy
    assert [call[:3] for call in run.calls] == [(s.width, s.height, s.samples) for s in schedule(40, 30, 4)]
    assert all(call[3].settings is scene.settings for call in run.calls)
    frame = viewport.frame
    assert frame.resolution == (40, 30) and frame.samples == 4 and frame.pixels.shape == (30, 40, 4)
    np.testing.assert_array_equal(frame.pixels, view_pixels(_constant_film(40, 30, 1.0), 40, 30))  # XYZ (1, 1, 1)
    assert viewport.status.startswith("4 samples in")
    viewport.close()


def _constant_film(width, height, value):
    film = Film(width, height)
    film.add(0, 0, 0, np.full((height, width, 3), value), np.zeros((height, width, 3)), 1)
    return film


def test_a_restart_stops_the_render_in_flight_at_once():
    """A new request returns at once on the main thread; the render in flight stops at its next unit,
    and only the new request's images are shown from then on."""
    run = StandInRun(unit=0.05, units=10_000)
    viewport = ViewportRenderer(run)
    first = _tracer_scene()
    viewport.render(first, "")
    while len(run.calls) < 1:
        time.sleep(0.005)
    time.sleep(0.2)
    second = _tracer_scene(samples=2)
    start = time.perf_counter()
    viewport.render(second, "")
    returned = time.perf_counter() - start
    while len(run.returned) < 1:
        time.sleep(0.005)
    stopped = run.returned[0] - start
    assert returned < 0.2, f"render() took {returned:.3f} s to return"
    assert stopped < 0.5, f"the render in flight stopped {stopped:.3f} s after the restart"
    assert viewport.busy
    while len(run.calls) < 2:
        time.sleep(0.005)
    assert run.calls[1][3].settings is second.settings  # the next render is the new request's
    viewport.close()


def test_a_burst_of_requests_renders_only_the_last():
    run = StandInRun(unit=0.02, units=2)
    viewport = ViewportRenderer(run)
    scenes_sent = [_tracer_scene(samples=n) for n in (1, 2, 3, 5)]
    for scene in scenes_sent:
        viewport.render(scene, "")
    assert viewport.wait(10)
    rendered = {id(call[3].settings) for call in run.calls}
    assert id(scenes_sent[-1].settings) in rendered and id(scenes_sent[1].settings) not in rendered
    assert viewport.frame.samples == 5
    viewport.close()


def test_a_moved_view_restarts_and_the_same_view_does_not():
    run = StandInRun()
    viewport = ViewportRenderer(run)
    scene = _tracer_scene()
    viewport.render(scene, "tcp://farm:8786")
    assert viewport.wait(10)
    calls = len(run.calls)
    assert not viewport.look_through(dataclasses.replace(scene.camera, to_world=scene.camera.to_world.copy()))
    assert not viewport.busy and len(run.calls) == calls
    assert viewport.look_through(dataclasses.replace(scene.camera, width=20, height=10))
    assert viewport.wait(10)
    assert run.calls[-1][:3] == (20, 10, 4) and viewport.frame.pixels.shape == (10, 20, 4)
    assert viewport.scheduler == "tcp://farm:8786"
    viewport.close()


def test_viewport_denoise_denoises_the_full_view():
    """With Viewport Denoise, the full view's image is the denoised film; a moved view keeps denoising."""
    box = scenes.medium(scenes.box_grid(size=(1.6, 1.6, 1.6), density=2.0), albedo=0.9)
    scene = scenes.scene(scenes.perspective_camera(48, 36), [box], [scenes.sun((1.0, 0.5, 1.0), strength=3.0)],
                         spp=4)
    viewport = ViewportRenderer()
    viewport.render(scene, "", denoised=True)
    assert viewport.wait(120) and viewport.frame.samples == 4, viewport.status
    film = render(scene).film  # same scene and seed: the same film
    np.testing.assert_allclose(viewport.frame.pixels, view_pixels(film, 48, 36, denoised=True), rtol=1e-5, atol=1e-6)
    assert not np.allclose(viewport.frame.pixels, view_pixels(film, 48, 36), rtol=1e-3, atol=1e-4)
    assert viewport.look_through(dataclasses.replace(scene.camera, width=24, height=18)) and viewport.denoised
    viewport.close()


def test_failures_are_shown_not_raised():
    viewport = ViewportRenderer(StandInRun(error=SpectralError("grid 'density' in smoke.vdb is empty")))
    viewport.render(_tracer_scene(), "")
    assert viewport.wait(10)
    assert viewport.status == "grid 'density' in smoke.vdb is empty" and viewport.frame is None
    viewport.close()
    viewport = ViewportRenderer(StandInRun(error=ZeroDivisionError("bug")))
    viewport.render(_tracer_scene(), "")
    assert viewport.wait(10)
    assert "failed unexpectedly" in viewport.status and "ZeroDivisionError" in viewport.status
    viewport.fail("the scene has no lights")
    assert not viewport.busy and viewport.frame is None and viewport.status == "the scene has no lights"
    assert not viewport.look_through(_tracer_scene().camera)  # nothing to render until the next export
    viewport.close()


# ------------------------------------------------------------------ the camera, against Blender's own


def _camera_view(camera_object, width, height):
    """A stand-in for a 3D view in camera view whose camera frame fills the region exactly: Blender's view
    and window matrices are then the camera's inverse world matrix and its projection matrix."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    window = camera_object.calc_matrix_camera(depsgraph, x=width, y=height)
    region_data = SimpleNamespace(view_matrix=camera_object.matrix_world.inverted(), window_matrix=window)
    return SimpleNamespace(region=SimpleNamespace(width=width, height=height), region_data=region_data)


@pytest.mark.parametrize("kind, fit, shift", [("PERSP", "AUTO", (0.0, 0.0)), ("PERSP", "VERTICAL", (0.15, -0.1)),
                                              ("ORTHO", "AUTO", (-0.2, 0.05)), ("ORTHO", "HORIZONTAL", (0.0, 0.3))])
def test_the_camera_view_is_the_scene_camera(registered, tmp_path, kind, fit, shift):
    scene, _cloud = basic_scene(tmp_path)
    scene.render.resolution_x, scene.render.resolution_y = 30, 44
    camera_object = scene.camera
    camera_object.rotation_euler = (math.radians(80), 0.0, math.radians(10))
    data = camera_object.data
    data.type, data.sensor_fit, data.lens, data.ortho_scale = kind, fit, 35.0, 3.0
    data.shift_x, data.shift_y = shift
    view = region_camera(_camera_view(camera_object, 30, 44))
    exported = export_camera(bpy.context.evaluated_depsgraph_get().scene_eval, camera_object)
    assert (view.width, view.height, view.kind) == (30, 44, exported.kind)
    np.testing.assert_allclose(camera_extent(view), camera_extent(exported), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(view.to_world, exported.to_world, atol=1e-5)


# -------------------------------------------------- the engine's view_update and view_draw, rendering


class EngineStandIn:
    """The engine's viewport methods on a plain object (Blender alone makes RenderEngine instances), with
    what they call of the RenderEngine API recorded."""

    view_update = SpectralVolumeEngine.view_update
    view_draw = SpectralVolumeEngine.view_draw
    _viewport = SpectralVolumeEngine._viewport
    _show_stats = SpectralVolumeEngine._show_stats

    def __init__(self):
        self.redraws, self.stats, self.display_space = 0, "", []

    def tag_redraw(self):
        self.redraws += 1

    def update_stats(self, _stats, info):
        self.stats = info

    def bind_display_space_shader(self, scene):
        self.display_space.append(scene.name)

    def unbind_display_space_shader(self):
        self.display_space.append(None)


@pytest.fixture(scope="module")
def gpu_module():
    """Blender-as-a-module draws (offscreen, through EGL) once `gpu.init()` has run."""
    import gpu

    gpu.init()
    return gpu


def _draw(gpu, engine, context, depsgraph) -> np.ndarray:
    """Call `view_draw` into an offscreen float buffer of the region's size; its pixels, bottom row first."""
    from mathutils import Matrix

    width, height = context.region.width, context.region.height
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    try:
        with offscreen.bind():
            framebuffer = gpu.state.active_framebuffer_get()
            framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0))
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():  # region pixels, as Blender draws
                gpu.matrix.load_identity()
                gpu.matrix.load_projection_matrix(Matrix.Translation((-1.0, -1.0, 0.0))
                                                  @ Matrix.Diagonal((2.0 / width, 2.0 / height, 1.0, 1.0)))
                engine.view_draw(context, depsgraph)
            pixels = framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT")
            return np.array(pixels.to_list(), dtype=np.float32).reshape(height, width, 4)
    finally:
        offscreen.free()


def _assert_same_render(frame, film, what):
    """The viewport's image matches a film of the same view and samples: luminance within 5σ per pixel."""
    rec709_y = np.array([0.2126, 0.7152, 0.0722])
    height, width = film.height, film.width
    expected = view_pixels(film, width, height)
    assert frame.pixels.shape == expected.shape, what
    difference = np.abs((frame.pixels[..., :3] - expected[..., :3]) @ rec709_y)
    sigma = np.sqrt(2.0 * blender_rows(film.variance).reshape(height, width, 3)[..., 1])
    assert np.all(difference <= 5.0 * sigma + 1e-6), f"{what}: largest difference {difference.max():.3g}"
    assert expected[..., 1].max() > 0 and frame.pixels[..., 3].min() == 1.0


def _f12_film(samples):
    """What F12 renders of the context's scene (its camera, its export), at `samples`."""
    return render(export_scene(bpy.context.evaluated_depsgraph_get()).scene, spp=samples).film


@pytest.mark.slow
def test_the_viewport_renders_and_draws_what_f12_renders(registered, tmp_path, gpu_module):
    scene, cloud = basic_scene(tmp_path)
    tiny_render(scene, 32, 24, samples=64)
    scene.spectral.preview_samples = 6
    scene.render.engine = "SPECTRAL_VOLUME"
    context = _camera_view(scene.camera, 32, 24)
    engine = EngineStandIn()
    engine.view_update(context, bpy.context.evaluated_depsgraph_get())
    assert engine.viewport.busy and engine.viewport.wait(300)
    _assert_same_render(engine.viewport.frame, _f12_film(6), "first render")
    assert engine.viewport.frame.samples == 6

    drawn = _draw(gpu_module, engine, context, bpy.context.evaluated_depsgraph_get())
    np.testing.assert_allclose(drawn, engine.viewport.frame.pixels, rtol=2e-3, atol=1e-4)  # through half floats
    assert engine.display_space == [scene.name, None]
    assert engine.stats.startswith("Spectral Volume | Viewport: 6 samples in") and engine.redraws == 0

    # An edit (the material's density), then the view moving: each restarts, each gives F12's image.
    cloud.material_slots[0].material.spectral.density_scale = 12.0
    engine.view_update(context, bpy.context.evaluated_depsgraph_get())
    assert engine.viewport.wait(60)
    _assert_same_render(engine.viewport.frame, _f12_film(6), "after the edit")
    scene.camera.location.x += 0.3
    moved, rendered = _camera_view(scene.camera, 32, 24), engine.viewport.scene
    _draw(gpu_module, engine, moved, bpy.context.evaluated_depsgraph_get())
    assert engine.viewport.scene is not rendered  # the moved view restarted the render
    assert engine.viewport.wait(60)
    _assert_same_render(engine.viewport.frame, _f12_film(6), "after the view moved")
    engine.viewport.close()


def test_add_on_setting_edits_reach_the_viewport(registered, tmp_path):
    """The add-on's settings of materials, lights, the World and the scene reach the viewport's export
    without re-evaluating its depsgraph (their evaluated copies do not follow property edits)."""
    scene, cloud = basic_scene(tmp_path)
    scene.world = bpy.data.worlds.new("World")
    scene.world.spectral.enabled = True
    scene.world.spectral.strength = 0.5
    context = _camera_view(scene.camera, 16, 12)
    bpy.context.evaluated_depsgraph_get()
    scene.spectral.seed, scene.spectral.preview_samples, scene.world.spectral.strength = 7, 3, 2.5
    scene.spectral.viewport_denoise = True
    cloud.material_slots[0].material.spectral.density_scale = 12.0
    bpy.data.lights["Sun"].spectral.unit = "radiant"
    exported = export_scene(bpy.context.evaluated_depsgraph_get(), view=region_camera(context)).scene
    assert exported.settings.seed == 7 and exported.settings.spp == scene.spectral.samples
    assert [light.strength for light in exported.lights if light.kind == "environment"] == [2.5]
    assert [light.unit for light in exported.lights if light.kind == "sun"] == ["radiant"]
    assert [medium.density_scale for medium in exported.media] == [12.0]
    engine = EngineStandIn()
    engine.view_update(context, bpy.context.evaluated_depsgraph_get())
    assert engine.viewport.scene.settings.spp == 3 and engine.viewport.scene.settings.seed == 7
    assert engine.viewport.denoised
    engine.viewport.close()


def test_view_draw_asks_for_redraws_while_a_render_is_in_flight():
    engine = EngineStandIn()
    engine.viewport, engine.viewport_notes = ViewportRenderer(StandInRun(unit=0.05, units=10_000)), ["a note"]
    scene = _tracer_scene()
    engine.viewport.render(scene)
    region_data = SimpleNamespace(view_matrix=np.linalg.inv(scene.camera.to_world),
                                  window_matrix=_orthographic_matrix(-1.0, 1.0, -0.75, 0.75, 0.1, 10.0))
    context = SimpleNamespace(region=SimpleNamespace(width=40, height=30), region_data=region_data)
    engine.view_draw(context, None)  # no image yet: nothing to draw
    assert engine.redraws == 1 and engine.display_space == []
    assert engine.stats.startswith("Spectral Volume | Viewport: ") and engine.stats.endswith(" | a note")
    engine.viewport.fail("stopped")
    engine.view_draw(context, None)
    assert engine.redraws == 1 and engine.stats == "Spectral Volume | Viewport: stopped | a note"
    engine.viewport.close()


def test_an_export_error_is_shown_in_the_viewport(registered, tmp_path, gpu_module):
    scene, _cloud = basic_scene(tmp_path)
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    context = _camera_view(scene.camera, 16, 12)
    engine = EngineStandIn()
    engine.view_update(context, bpy.context.evaluated_depsgraph_get())
    assert not engine.viewport.busy and engine.viewport.frame is None
    drawn = _draw(gpu_module, engine, context, bpy.context.evaluated_depsgraph_get())
    assert not drawn.any() and engine.display_space == []  # nothing drawn
    assert "the scene has no lights" in engine.stats and engine.redraws == 0
    engine.viewport.close()


@pytest.mark.slow
def test_a_restart_stops_a_real_render_quickly(registered, tmp_path):
    """With the kernel: after an edit the render in flight returns within 0.5 s (its units are 0.05 s)
    and the new render's first image, at 1/8 resolution, follows."""
    scene, _cloud = basic_scene(tmp_path)
    exported = export_scene(bpy.context.evaluated_depsgraph_get()).scene
    camera = dataclasses.replace(exported.camera, width=160, height=120)
    long_render = dataclasses.replace(exported, camera=camera,
                                      settings=dataclasses.replace(exported.settings, spp=100_000))
    sizes, returned = [], []

    def run(step_scene, *args, **options):
        sizes.append((step_scene.camera.width, step_scene.camera.height))
        result = tracer_job.render_tracer(step_scene, *args, **options)
        returned.append((time.perf_counter(), result.cancelled))
        return result

    viewport = ViewportRenderer(run)
    viewport.render(long_render)
    deadline = time.perf_counter() + 300
    while (viewport.frame is None or viewport.frame.resolution != (160, 120)) and time.perf_counter() < deadline:
        time.sleep(0.01)
    assert viewport.frame.resolution == (160, 120)
    time.sleep(0.3)
    start = time.perf_counter()
    request = viewport.render(dataclasses.replace(long_render, camera=dataclasses.replace(camera, shift_x=0.1)))
    restarted = time.perf_counter() - start
    while viewport.frame.request != request and time.perf_counter() < deadline:
        time.sleep(0.005)
    first_image = time.perf_counter() - start
    stopped_at, cancelled = returned[len(RESOLUTION_DIVISORS)]  # the full view's render, in flight
    assert cancelled and restarted < 0.2, f"render() took {restarted:.3f} s to return"
    assert stopped_at - start < 0.5, f"the render in flight returned {stopped_at - start:.3f} s after the edit"
    assert sizes[len(RESOLUTION_DIVISORS) + 1] == (20, 15) and first_image < 5.0
    viewport.close()
