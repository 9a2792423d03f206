"""The Rendered viewport's renders, away from Blender's data: restarted on every change, refined
progressively, on one background thread.

`ViewportRenderer.render(scene)` hands over a finished tracer Scene (exported on the main thread, with the
view's camera and the Viewport Samples): the render in flight stops at its next unit of work and the new
one starts. Each render goes through the resolution steps of `schedule` (1/8, 1/4 and 1/2 of the view's
pixels per axis, one sample each) and then renders the full view up to the scene's sample count, whose
passes refine the image (its first pass fills in the half-resolution image as it goes). `frame` is the
latest image, at the view's size (low resolutions scaled up by nearest neighbour), for the draw step to
pick up on the main thread. With Viewport Denoise on, the full view's images are denoised (OIDN's fast
quality, addon/tracer/denoise.py) once every pixel has a sample; the low-resolution steps stay raw. One
thread renders every request in turn, so two kernels never run at once and a burst of edits renders only
the last one. The thread never touches `bpy`; renders go through `render_tracer` (this computer or the Dask
farm), like F12's tracer job's; unlike a render job (addon/jobs/), one renderer serves request after
request, each cancelling the last. Its pixels are laid out as Blender's (addon/output.py).
"""

import dataclasses
import threading
import time
from dataclasses import dataclass

import numpy as np

from ..jobs.tracer_job import render_tracer
from ..output import blender_rows, with_alpha
from ..tracer.denoise import denoised_rgb
from ..tracer.errors import SpectralError
from ..tracer.fireflies import as_finished
from ..tracer.progress import Throttle
from ..tracer.scene import Camera, Scene

RESOLUTION_DIVISORS = (8, 4, 2)  # the quick low-resolution steps before the full view, 1 sample each
UNIT_SECONDS = 0.05  # the render's units of work: a change stops the render in flight within about this
REFRESH_SECONDS = 0.1  # the full view's image is converted for display at most this often…
REFRESH_COST_RATIO = 10  # …and less often when converting takes over 1/ratio of the time between
DENOISE_QUALITY = "fast"  # OIDN's quality for the viewport: 0.17–0.19 s at 512×512 (2 cores), half "high"'s


@dataclass(frozen=True)
class Step:
    """One render of the progressive schedule: the view at width × height pixels, `samples` per pixel."""

    width: int
    height: int
    samples: int


def schedule(width: int, height: int, samples: int) -> list[Step]:
    """The renders that refine a width × height view up to `samples` per pixel: one sample at each of
    `RESOLUTION_DIVISORS` (steps that would repeat a size, in small views, are left out), then the full view."""
    steps = []
    for divisor in RESOLUTION_DIVISORS:
        step = Step(-(-width // divisor), -(-height // divisor), 1)
        if step.width * step.height < width * height and step not in steps:
            steps.append(step)
    return steps + [Step(width, height, samples)]


def resized(camera: Camera, width: int, height: int) -> Camera:
    """`camera` rendering the same frame at width × height pixels (the pixel aspect absorbs the rounding,
    so every step sees exactly the view's frame)."""
    pixel_aspect = camera.pixel_aspect * (camera.width / width) / (camera.height / height)
    return dataclasses.replace(camera, width=width, height=height, pixel_aspect=pixel_aspect)


def same_camera(a: Camera, b: Camera) -> bool:
    return all(np.array_equal(getattr(a, field.name), getattr(b, field.name)) for field in dataclasses.fields(Camera))


def view_camera(view_matrix, window_matrix, width: int, height: int) -> Camera:
    """The tracer Camera of a 3D view (Blender's RegionView3D `view_matrix` and `window_matrix`, as 4×4
    arrays) at width × height pixels. The window matrix says everything else: perspective (its last row is
    (0, 0, −1, 0)) or orthographic, the frame's extent and its shift; in camera view it holds the scene
    camera's lens, sensor fit and shift, and the view's zoom and offset of the camera frame. An
    orthographic view sees from its near clipping plane, which lies behind the view's origin in free views
    (Blender clips them from −clip_end/2): the tracer's orthographic camera starts there."""
    projection = np.asarray(window_matrix, dtype=np.float64)
    to_world = np.linalg.inv(np.asarray(view_matrix, dtype=np.float64))
    to_world[:3, :3] /= np.linalg.norm(to_world[:3, :3], axis=0)  # the view's scale (none, or the camera's)
    extent_x, extent_y = 2.0 / projection[0, 0], 2.0 / projection[1, 1]
    perspective = projection[3, 3] == 0.0
    if perspective:  # x_clip = m00 x + m02 z with w = −z: the frame's centre at z = −1 is m02 / m00
        centre_x, centre_y = projection[0, 2] / projection[0, 0], projection[1, 2] / projection[1, 1]
    else:  # x_ndc = m00 x + m03
        centre_x, centre_y = -projection[0, 3] / projection[0, 0], -projection[1, 3] / projection[1, 1]
        near = (1.0 + projection[2, 3]) / projection[2, 2]  # z_ndc = m22 z + m23 is −1 at z = −near
        if near < 0.0:
            to_world[:3, 3] -= near * to_world[:3, 2]  # back along the view (+z), behind its origin
    return Camera(to_world=np.ascontiguousarray(to_world), width=int(width), height=int(height),
                  kind="perspective" if perspective else "orthographic", fov=2.0 * np.arctan(extent_x / 2.0),
                  ortho_scale=extent_x, sensor_fit="HORIZONTAL", shift_x=centre_x / extent_x,
                  shift_y=centre_y / extent_x, pixel_aspect=(extent_x / extent_y) * (height / width))


def view_pixels(film, width: int, height: int, denoised: bool = False) -> np.ndarray:
    """Film → (height, width, 4) float32 linear Rec.709 RGBA, bottom row first (as GPU textures), scaled
    up to width × height by nearest neighbour; with `denoised`, denoised first."""
    rgb = denoised_rgb(film, DENOISE_QUALITY) if denoised else film.rgb()
    pixels = blender_rows(with_alpha(rgb, film.alpha)).reshape(film.height, film.width, 4)
    if (film.width, film.height) == (width, height):
        return pixels
    rows = np.arange(height) * film.height // height
    columns = np.arange(width) * film.width // width
    return pixels[rows[:, None], columns[None, :]]


def filled(pixels: np.ndarray, film, behind: np.ndarray | None) -> np.ndarray:
    """`pixels` of a full-size `film` whose first pass is still under way, with the pixels it has no sample
    for yet taken from `behind` (the previous image, the same size), so no holes show."""
    holes = (film.pixel_samples.min(axis=0) == 0)[::-1]  # bottom row first, as the pixels
    if behind is None or behind.shape != pixels.shape or not holes.any():
        return pixels
    pixels[holes] = behind[holes]
    return pixels


@dataclass(frozen=True)
class Frame:
    """An image for the draw step: `pixels` (see `view_pixels`), rendered at `resolution` (width, height)
    with `samples` per pixel (0 while the full view's first pass fills the previous image), for request
    number `request`."""

    pixels: np.ndarray
    resolution: tuple[int, int]
    samples: int
    request: int


class ViewportRenderer:
    """Owns the viewport's render thread. Main thread: `render`, `fail`, `close`, and reading `frame`,
    `status` and `busy`. `run` (default `jobs.tracer_job.render_tracer`) renders one step; tests pass a stand-in."""

    def __init__(self, run=render_tracer):
        self._run = run
        self._condition = threading.Condition()
        self._requested = 0  # number of the latest request; a render whose number differs stops
        self._finished = 0  # number of the latest request whose render ended (done, failed or cancelled)
        self._pending = None  # (number, scene, scheduler, denoised) not picked up by the thread yet
        self._closed = False
        self.scene = None  # the scene of the latest request
        self.scheduler = ""  # and its Dask scheduler ("": this computer)
        self.denoised = False  # and whether its full view is denoised
        self.frame = None  # the latest image of the latest request (None until its first one)
        self.status = ""  # one line for the viewport's stats: progress, or why nothing renders
        self._thread = threading.Thread(target=self._work, name="spectral-viewport", daemon=True)
        self._thread.start()

    def render(self, scene: Scene, scheduler: str = "", denoised: bool = False) -> int:
        """Render `scene` from now on (returns at once: the render in flight stops at its next unit), its
        full view denoised if `denoised`; the request's number, which its frames carry."""
        with self._condition:
            self._requested += 1
            self._pending = (self._requested, scene, scheduler, denoised)
            self.scene, self.scheduler, self.denoised = scene, scheduler, denoised
            self.status = "Starting"
            self._condition.notify_all()
            return self._requested

    def look_through(self, camera: Camera) -> bool:
        """Render the latest scene through `camera` when that differs from its own (the view moved or was
        resized); True if that restarted the render."""
        if self.scene is None or same_camera(camera, self.scene.camera):
            return False
        self.render(dataclasses.replace(self.scene, camera=camera), self.scheduler, self.denoised)
        return True

    def fail(self, message: str) -> None:
        """Stop rendering and show `message` instead of an image (bad input: the scene cannot be exported)."""
        with self._condition:
            self._requested += 1
            self._finished = self._requested
            self._pending, self.scene, self.frame, self.status = None, None, None, message
            self._condition.notify_all()

    def close(self) -> None:
        """Stop the thread (at its next unit of work; this does not wait)."""
        with self._condition:
            self._closed = True
            self._condition.notify_all()

    @property
    def busy(self) -> bool:
        """Whether a render is in flight (the draw step then asks for redraws, to show its progress)."""
        return self._finished != self._requested

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the latest request is rendered (or failed); False on timeout. For scripts and tests."""
        with self._condition:
            return self._condition.wait_for(lambda: not self.busy or self._closed, timeout)

    def _work(self) -> None:
        while True:
            with self._condition:
                self._condition.wait_for(lambda: self._pending is not None or self._closed)
                if self._closed:
                    return
                (number, scene, scheduler, denoised), self._pending = self._pending, None
            status = self._refine(number, scene, scheduler, denoised)
            with self._condition:
                if number == self._requested:
                    self._finished, self.status = number, status
                    self._condition.notify_all()

    def _cancelled(self, number: int) -> bool:
        return number != self._requested or self._closed

    def _refine(self, number: int, scene: Scene, scheduler: str, denoised: bool = False) -> str:
        """Run the schedule of request `number`; the status line it ends with."""
        camera = scene.camera
        steps = schedule(camera.width, camera.height, scene.settings.spp)
        start = time.perf_counter()
        try:
            for step in steps:
                if not self._render_step(number, scene, scheduler, step, step is steps[-1], denoised):
                    return ""
        except SpectralError as problem:
            return str(problem)
        except Exception as problem:  # noqa: BLE001 - shown in the viewport: the thread must not die silently
            return f"the viewport render failed unexpectedly: {problem!r}"
        return f"{steps[-1].samples} samples in {time.perf_counter() - start:.1f} s"

    def _render_step(self, number: int, scene: Scene, scheduler: str, step: Step, last: bool,
                     denoised: bool = False) -> bool:
        """Render one step and show its image (denoised if `denoised` and this is the full view); False if
        cancelled."""
        width, height = scene.camera.width, scene.camera.height
        step_scene = dataclasses.replace(scene, camera=resized(scene.camera, step.width, step.height))
        self._show(number, status=f"0/{step.samples} samples" if last else f"preview at {step.width}×{step.height}")
        throttle = Throttle(REFRESH_SECONDS, REFRESH_COST_RATIO)

        def progress(film, fraction):
            if last:
                self._show(number, status=f"{int(fraction * step.samples)}/{step.samples} samples")
                if throttle.due():
                    with throttle.timed():
                        shown = self.frame
                        behind = shown.pixels if shown is not None and shown.request == number else None
                        complete = bool(film.pixel_samples.min() > 0)
                        shown_film = as_finished(film, scene.settings.firefly_threshold)
                        pixels = filled(view_pixels(shown_film, width, height, denoised and complete), film, behind)
                        self._show(number, frame=Frame(pixels, (step.width, step.height), int(film.samples.min()),
                                                       number))

        result = self._run(step_scene, scheduler, spp=step.samples, progress=progress,
                           cancel=lambda: self._cancelled(number), notice=lambda text: self._show(number, status=text),
                           unit_seconds=UNIT_SECONDS)
        if result.cancelled:
            return False
        self._show(number, frame=Frame(view_pixels(result.film, width, height, denoised and last),
                                       (step.width, step.height),
                                       step.samples, number))
        return True

    def _show(self, number: int, frame: Frame | None = None, status: str | None = None) -> None:
        """Publish what request `number` has to show, unless a newer request replaced it."""
        with self._condition:
            if number != self._requested:
                return
            if frame is not None:
                self.frame = frame
            if status is not None:
                self.status = status
