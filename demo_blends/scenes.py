"""The demo scenes as tracer `Scene`s, built in code: no files, no downloads. The one source of their numbers.

Each builder takes the image size and samples per pixel and returns a `Scene`. `build_blends` writes
these scenes as .blend files (tests/demos/test_blends.py checks that each file exports back to the
scene built here); `make demo` renders the files and `metrics` computes the figures from the films.

World conventions: Blender's, z up, lengths in Blender units. Directions to lights are given as
(elevation, azimuth) in degrees, azimuth measured from +y (the direction the cameras look along)
towards +x.
"""

import numpy as np

from addon.tracer import spectra
from addon.tracer.procedural import cloud_grid
from addon.tracer.builders import (cell_centres, direction, environment, medium, perspective, sampled_grid, scene,
                                   smooth_step, sun)
from addon.tracer.scene import BlackbodyEmission, Camera, Fluorescence, Grid, Medium, Scene, Surface, look_at
from addon.tracer.wavelengths import GRID

SEED = 1  # every demo renders with this seed: the same image on every run


def uniform(x, y, z):
    """Density 1 everywhere (a field for `sampled_grid`)."""
    return np.ones(np.broadcast_shapes(x.shape, y.shape, z.shape))


# ----------------------------------------------------------------------------- Rayleigh skies

FLAT = spectra.constant(1.0)  # the report's sun: equal energy at every wavelength (not D65)
ATMOSPHERE_TOP = 1.0  # thickness of the slab of air
ATMOSPHERE_HALF_WIDTH = 40.0  # wide enough that a sun 4° above the horizon still shines through air
SUN_ANGLE = 2.0  # degrees; the real sun's is 0.53, four times wider keeps its disc visible at 256 px
SKY_CAMERA_HEIGHT = 0.06


def ground(albedo: float = 0.35) -> Medium:
    """A dense grey layer below z = 0 standing in for the ground."""
    w = ATMOSPHERE_HALF_WIDTH
    grid = sampled_grid(uniform, (4, 4, 4), (-w, -w, -0.2), (w, w, 0.0))
    return medium(grid, 200.0, name="ground", albedo=albedo)


def atmosphere(name: str, extinction, **optics) -> Medium:
    """A slab of air from the ground to ATMOSPHERE_TOP, constant density 1, σ_t = extinction(λ)."""
    w = ATMOSPHERE_HALF_WIDTH
    grid = sampled_grid(uniform, (8, 8, 32), (-w, -w, 0.0), (w, w, ATMOSPHERE_TOP))
    return medium(grid, 1.0, name=name, extinction=extinction, **optics)


def sky_camera(width: int, height: int, pitch: float, fov: float = 100.0) -> Camera:
    """A camera just above the ground looking along +y, tilted `pitch` degrees up."""
    eye = np.array([0.0, 0.0, SKY_CAMERA_HEIGHT])
    return perspective(eye, eye + direction(pitch, 0.0), width, height, fov)


# The report's setup: albedo 0.8 everywhere, g rising from 0 at 380 nm to strongly forward at 700 nm.
# It rises as a square root, so greens are already fairly forward: a linear rise leaves the sky far from
# the sun cyan (dominant wavelength 491 nm, hue 205°) instead of blue (485 nm, 233°).
REPORT_ALBEDO = 0.8
REPORT_G_MAX = 0.95
REPORT_TAU = 0.5  # vertical optical depth (the same at every λ)
REPORT_SUN = (22.0, 32.0)  # elevation, azimuth (degrees)


def report_anisotropy() -> spectra.Spectrum:
    return spectra.Spectrum(REPORT_G_MAX * np.sqrt(np.clip((GRID - 380.0) / (700.0 - 380.0), 0.0, 1.0)))


def rayleigh_report(width: int, height: int, spp: int) -> Scene:
    """The report's Rayleigh imitation: a flat-spectrum sun through a grey slab whose anisotropy grows
    with wavelength, so red goes on forward (around the sun) and blue is spread over the sky."""
    air = atmosphere("air", REPORT_TAU / ATMOSPHERE_TOP, albedo=REPORT_ALBEDO,
                     g=report_anisotropy())
    light = sun(direction(*REPORT_SUN), 5.0, angle=np.radians(SUN_ANGLE), spectrum=FLAT, name="sun")
    return scene(sky_camera(width, height, pitch=14.0), (air, ground()), (light,), spp=spp, seed=SEED)


# True Rayleigh: σ_t ∝ λ⁻⁴, Rayleigh phase function, no absorption; a low sun (sunset). Pure Rayleigh
# air cannot give a deep blue zenith and a red sun at once (a flat slab: zenith radiance ∝
# e^(−τ) − e^(−mτ) for air mass m, which is pale once τ(450 nm)·m ≳ 1): this optical depth and sun
# height give a blue upper sky and an orange sun.
RAYLEIGH_TAU_550 = 0.12  # vertical optical depth at 550 nm (the Earth's is about 0.1)
RAYLEIGH_SUN = (4.0, 32.0)


def rayleigh_true(width: int, height: int, spp: int) -> Scene:
    """Air with extinction ∝ λ⁻⁴ and the Rayleigh phase function at sunset: blue overhead, the sun
    and the sky around it reddened by the long path through the air."""
    # Only visible light is traced, so the λ⁻⁴ law stops at 360 nm: below it would only raise the majorant.
    extinction = spectra.Spectrum(np.where(GRID >= 360.0, (550.0 / GRID) ** 4, 0.0) * RAYLEIGH_TAU_550 / ATMOSPHERE_TOP)
    air = atmosphere("air", extinction, albedo=1.0, phase="rayleigh")
    light = sun(direction(*RAYLEIGH_SUN), 3.0, angle=np.radians(SUN_ANGLE), spectrum=FLAT, name="sun")
    return scene(sky_camera(width, height, pitch=24.0), (air, ground()), (light,), spp=spp, seed=SEED)


# ----------------------------------------------------------------------------- shapes for procedural volumes


def ellipsoid(centre, radii):
    """Approximate signed distance to an ellipsoid (exact for spheres; negative inside)."""
    centre, radii = np.asarray(centre, dtype=np.float64), np.asarray(radii, dtype=np.float64)

    def sdf(x, y, z):
        q = np.sqrt(((x - centre[0]) / radii[0]) ** 2 + ((y - centre[1]) / radii[1]) ** 2
                    + ((z - centre[2]) / radii[2]) ** 2)
        return (q - 1.0) * radii.min()

    return sdf


def capsule(a, b, radius):
    """Signed distance to the segment a–b thickened by `radius`."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    axis = b - a

    def sdf(x, y, z):
        px, py, pz = x - a[0], y - a[1], z - a[2]
        t = np.clip((px * axis[0] + py * axis[1] + pz * axis[2]) / (axis @ axis), 0.0, 1.0)
        return np.sqrt((px - t * axis[0]) ** 2 + (py - t * axis[1]) ** 2 + (pz - t * axis[2]) ** 2) - radius

    return sdf


def union(*shapes, blend: float = 0.06):
    """Smooth union of signed distances (polynomial smooth minimum over `blend` world units)."""

    def sdf(x, y, z):
        distance = shapes[0](x, y, z)
        for shape in shapes[1:]:
            other = shape(x, y, z)
            h = np.clip(0.5 + 0.5 * (other - distance) / blend, 0.0, 1.0)
            distance = other + (distance - other) * h - blend * h * (1.0 - h)
        return distance

    return sdf


def solid(sdf, edge: float):
    """Density 1 inside a signed-distance shape, 0 outside, with a smooth edge `edge` world units wide."""
    return lambda x, y, z: np.clip(0.5 - sdf(x, y, z) / edge, 0.0, 1.0)


def both_sides(part):
    """`part(side)` for side = +1 and −1: a body part and its mirror image across x = 0."""
    return part(1.0), part(-1.0)


# ----------------------------------------------------------------------------- fluorescent frog

# The lamp: only 275–450 nm (UV plus violet), as in the report.
UV_WINDOW = (275.0, 450.0)
UV_LAMP = spectra.window(spectra.constant(1.0), *UV_WINDOW)
# The fluorophore absorbs UV (and a little violet) and re-emits green around 540 nm.
FROG_EXCITATION = spectra.Spectrum(spectra.gaussian(340.0, 20.0).values * (1.0 - smooth_step(410.0, 20.0)))
FROG_EMISSION = spectra.gaussian(540.0, 30.0)
FROG_QUANTUM_YIELD = 0.5
# Fluorophore density: optical depth 8 per unit at the excitation peak, so UV is absorbed in a skin a
# tenth of a unit thick. Kept this low on purpose: the kernel traces fluorescence from the camera as a
# null-collision event whose weights grow like exp(∫σ_fl ds) along the ray (σ_fl here ≈ 2.7 per
# unit); at 20 per unit the frog's far side is missed in practice (estimates 20–35 % low and
# direction dependent, although unbiased in expectation).
FROG_DENSITY = 8.0
FROG_BOX = ((-1.3, -1.25, 0.0), (1.3, 1.45, 1.15))
EYES = ((0.27, 0.72, 0.86), (-0.27, 0.72, 0.86))


def frog_shape():
    """A sitting frog facing +y, about 2.6 units long, from ellipsoids and capsules (signed distance)."""
    body = ellipsoid((0.0, -0.15, 0.42), (0.55, 0.78, 0.38))
    head = ellipsoid((0.0, 0.62, 0.58), (0.5, 0.42, 0.3))
    eyes = [ellipsoid(eye, (0.14, 0.14, 0.13)) for eye in EYES]
    arms = both_sides(lambda s: capsule((s * 0.35, 0.35, 0.36), (s * 0.55, 0.6, 0.06), 0.09))
    hands = both_sides(lambda s: ellipsoid((s * 0.6, 0.72, 0.04), (0.16, 0.14, 0.04)))
    thighs = both_sides(lambda s: capsule((s * 0.42, -0.55, 0.32), (s * 0.88, -0.1, 0.28), 0.17))
    shins = both_sides(lambda s: capsule((s * 0.88, -0.1, 0.28), (s * 0.72, -0.78, 0.1), 0.12))
    feet = both_sides(lambda s: capsule((s * 0.72, -0.78, 0.05), (s * 1.08, -0.25, 0.04), 0.07))
    return union(body, head, *eyes, *arms, *hands, *thighs, *shins, *feet)


def frog_medium(cells=(96, 100, 44)) -> Medium:
    """The frog's body: a fluorophore and nothing else, so it is transparent to visible light and every
    bit of light it sends out is fluorescence."""
    grid = sampled_grid(solid(frog_shape(), edge=0.04), cells, *FROG_BOX)
    fluorescence = Fluorescence(excitation=FROG_EXCITATION, emission=FROG_EMISSION,
                                quantum_yield=FROG_QUANTUM_YIELD)
    return medium(grid, FROG_DENSITY, name="frog", extinction=0.0, albedo=0.0, fluorescence=fluorescence)


def frog_pupils() -> Medium:
    """Black pupils at the front of the eyes (they absorb everything; not fluorescent)."""
    pupils = union(*(ellipsoid(np.add(eye, (0.0, 0.09, 0.01)), (0.075, 0.06, 0.075)) for eye in EYES))
    grid = sampled_grid(solid(pupils, edge=0.02), (48, 16, 16), (-0.45, 0.72, 0.75), (0.45, 0.92, 1.0))
    return medium(grid, 200.0, name="pupils", albedo=0.0)


def lily_pad() -> Medium:
    """A white, non-fluorescent disc under the frog: it shows the colour of the lamp."""
    pad = solid(lambda x, y, z: np.maximum(np.hypot(x, y - 0.05) - 1.7, np.abs(z + 0.07) - 0.07), edge=0.03)
    grid = sampled_grid(pad, (72, 72, 6), (-1.8, -1.75, -0.16), (1.8, 1.85, 0.02))
    return medium(grid, 40.0, name="pad", albedo=0.5)


def fluorescent_frog(width: int, height: int, spp: int) -> Scene:
    """A frog lit by a UV/violet lamp glows green: the green comes only from fluorescence."""
    # Strengths are luminances (Y), and violet has very little: Y = 0.04 is already a bright violet.
    lamp = sun(direction(45.0, -30.0), 0.05, spectrum=UV_LAMP, name="UV lamp")
    fill = environment(0.001, UV_LAMP, name="UV fill")
    cam = perspective((-2.4, 4.6, 2.3), (0.0, 0.05, 0.35), width, height, 42.0)
    return scene(cam, (frog_medium(), lily_pad(), frog_pupils()), (lamp, fill), spp=spp, seed=SEED)


def fibonacci_directions(count: int) -> np.ndarray:
    """`count` unit vectors spread evenly over the sphere (equal-area Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (1.0 + np.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


ENERGY_LAMP = sun(direction(90.0), 0.05, spectrum=UV_LAMP, name="UV lamp overhead")  # no angle: never seen


def energy_views(body: Medium, box, size: int, spp: int, views: int = 16) -> list[Scene]:
    """A fluorescent body (inside `box`) alone under a lamp straight above it, seen by orthographic
    cameras from `views` directions over the whole sphere, each framing all of it: what
    `metrics.emitted_power` integrates into the power the body sends out."""
    lo, hi = np.array(box[0]), np.array(box[1])
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    cameras = []
    for view in fibonacci_directions(views):
        up = (0.0, 0.0, 1.0) if abs(view[2]) < 0.9 else (0.0, 1.0, 0.0)
        to_world = look_at(centre + 3.0 * radius * view, centre, up)
        cameras.append(Camera(to_world=to_world, width=size, height=size, kind="orthographic",
                              ortho_scale=2.0 * radius))
    return [scene(cam, (body,), (ENERGY_LAMP,), spp=spp, seed=SEED) for cam in cameras]


# ----------------------------------------------------------------------------- dense fluorescence: highlighter ink

# A pyranine-like highlighter dye: absorbs violet (405 nm; nothing above 460 nm, so it never absorbs
# its own light), emits green around 515 nm with quantum yield 0.9.
INK_EXCITATION = spectra.Spectrum(spectra.gaussian(405.0, 20.0).values * (1.0 - smooth_step(460.0, 15.0)))
INK_EMISSION = spectra.gaussian(515.0, 22.0)
INK_QUANTUM_YIELD = 0.9
INK_RADIUS, INK_HEIGHT = 0.3, 0.8
# The ink's optical depth at the excitation peak across the glass is 2 × 0.3 × 120 = 72 (σ_fl·d about 60 at
# the emission peak): all of the lamp's violet is absorbed in a skin at the lit side. Diluted 50×, 1.4.
INK_DENSITY = 120.0
INK_DILUTION = 50.0
INK_CENTRES = ((-0.4, 0.0), (0.4, 0.0))  # (x, y) of the ink glass and of the diluted one


def ink_box(centre) -> tuple:
    x, y = centre
    margin = INK_RADIUS + 0.02
    return (x - margin, y - margin, 0.0), (x + margin, y + margin, INK_HEIGHT + 0.02)


def ink_medium(name: str, centre, density: float, cells=(32, 32, 42)) -> Medium:
    """A glass-shaped cylinder of highlighter ink standing on z = 0: a fluorophore and nothing else."""
    x0, y0 = centre
    cylinder = lambda x, y, z: np.maximum(np.hypot(x - x0, y - y0) - INK_RADIUS,
                                          np.abs(z - INK_HEIGHT / 2) - INK_HEIGHT / 2)
    grid = sampled_grid(solid(cylinder, edge=0.02), cells, *ink_box(centre))
    fluorescence = Fluorescence(excitation=INK_EXCITATION, emission=INK_EMISSION, quantum_yield=INK_QUANTUM_YIELD)
    return medium(grid, density, name=name, extinction=0.0, albedo=0.0, fluorescence=fluorescence)


def highlighter_ink(width: int, height: int, spp: int) -> Scene:
    """Two glasses of highlighter ink under the frog's lamp: the dense one glows only in a thin skin
    facing the lamp, the one diluted 50× glows through its whole volume."""
    lamp = sun(direction(45.0, -30.0), 0.05, spectrum=UV_LAMP, name="UV lamp")
    fill = environment(0.001, UV_LAMP, name="UV fill")
    cam = perspective((-0.9, 2.6, 1.3), (0.0, 0.0, 0.36), width, height, 40.0)
    media = (ink_medium("ink", INK_CENTRES[0], INK_DENSITY),
             ink_medium("diluted ink", INK_CENTRES[1], INK_DENSITY / INK_DILUTION), lily_pad())
    return scene(cam, media, (lamp, fill), spp=spp, seed=SEED)


# ----------------------------------------------------------------------------- metamerism: two cubes

CUBE_EDGE = 1.0
CUBE_CENTRES = ((-0.85, 0.0, 0.5), (0.85, 0.0, 0.5))  # mirror images across x = 0
CUBE_DENSITY = 30.0  # optical depth 30 across a cube: a solid-looking block of scattering medium
METAMER_SUN = (55.0, 180.0)  # behind the camera, in the cubes' mirror plane
METAMER_FILL = 0.3  # environment luminance relative to the sun's


def cube(name: str, centre, albedo) -> Medium:
    """A cube of dense, isotropically scattering medium with the albedo spectrum `albedo`."""
    lo, hi = np.asarray(centre) - CUBE_EDGE / 2, np.asarray(centre) + CUBE_EDGE / 2
    grid = sampled_grid(uniform, (16, 16, 16), lo, hi)
    return medium(grid, CUBE_DENSITY, name=name, albedo=albedo)


def metamer_camera(width: int, height: int) -> Camera:
    return perspective((0.0, -4.4, 2.5), (0.0, 0.0, 0.4), width, height, 40.0)


def two_cubes(albedo_left, albedo_right, light: spectra.Spectrum, width: int, height: int, spp: int) -> Scene:
    """The two cubes side by side under a sun and a fill light that both have the spectrum `light`.
    The geometry is mirror-symmetric, so a cube's look depends only on its albedo, not its side."""
    media = (cube("left cube", CUBE_CENTRES[0], albedo_left), cube("right cube", CUBE_CENTRES[1], albedo_right))
    lights = (sun(direction(*METAMER_SUN), 1.0, spectrum=light, name="sun"), environment(METAMER_FILL, light))
    return scene(metamer_camera(width, height), media, lights, spp=spp, seed=SEED)


# The report's simple version: one cube scatters only the short half of the visible range, the other
# the short and the long ends; light: all of D65, or only D65's lower half (where the two agree).
LOW_END = 0.05 + 0.85 * (1.0 - smooth_step(500.0, 20.0))
HIGH_END = 0.85 * smooth_step(610.0, 20.0)
SIMPLE_ALBEDOS = (spectra.Spectrum(LOW_END), spectra.Spectrum(LOW_END + HIGH_END))
LOWER_HALF = (300.0, 570.0)  # D65's part where the two albedos agree
LIGHTS = {
    "D65": spectra.illuminant("D65"),
    "D65 lower half": spectra.window(spectra.illuminant("D65"), *LOWER_HALF),
    "A": spectra.illuminant("A"),
}


def metamerism_simple(light: str):
    """Builder of the report's two cubes under `light` ("D65" or "D65 lower half")."""
    def build(width: int, height: int, spp: int) -> Scene:
        return two_cubes(*SIMPLE_ALBEDOS, LIGHTS[light], width, height, spp)

    return build


# ----------------------------------------------------------------------------- fire


def smooth_noise(cells, scale_cells: float, seed: int, stretch=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Smooth random field on a grid of `cells`, features about `scale_cells` cells across (times
    `stretch` per axis), zero mean and unit standard deviation."""
    from scipy.ndimage import gaussian_filter

    field = gaussian_filter(np.random.default_rng(seed).standard_normal(tuple(cells)),
                            sigma=[scale_cells * s for s in stretch], mode="wrap")
    return ((field - field.mean()) / field.std()).astype(np.float32)


FIRE_CELLS = (56, 56, 96)
FIRE_BOX = ((-0.7, -0.7, 0.0), (0.7, 0.7, 2.4))
FLAME_HEIGHT = 1.25
FIRE_TEMPERATURES = (1000.0, 2000.0)  # kelvin: the flame's edge and its hottest core
FIRE_INTENSITY = 1.0  # scales the blackbody radiance (W·m⁻²·sr⁻¹·nm⁻¹)
MOON_TEMPERATURE = 9000.0  # kelvin: the colour of the bluish moonlight on the smoke


def fire_grids() -> tuple[Grid, Grid, Grid]:
    """Soot of the flame, its temperature (kelvin, 0 where cold) and the smoke rising above it."""
    (x, y, z), index_to_world = cell_centres(FIRE_CELLS, *FIRE_BOX)
    wobble = smooth_noise(FIRE_CELLS, 3.0, seed=3, stretch=(1.0, 1.0, 2.5))
    detail = smooth_noise(FIRE_CELLS, 1.5, seed=4, stretch=(1.0, 1.0, 2.0))
    sway = 0.06 * np.sin(3.0 * z)  # the plume leans and curls a little as it rises
    r = np.hypot(x - sway, y) * np.maximum(1.0 + 0.25 * wobble + 0.1 * detail, 0.3)
    h = z / FLAME_HEIGHT
    # Flame: a teardrop, widest a third of the way up; heat falls from the axis to its edge.
    flame_radius = 0.3 * np.sqrt(np.clip(1.0 - h, 0.0, 1.0)) * np.clip(2.5 * h + 0.35, 0.0, 1.0)
    heat = np.clip(1.0 - r / np.maximum(flame_radius, 1e-6), 0.0, 1.0)
    low, high = FIRE_TEMPERATURES
    temperature = np.where(heat > 0.0, low + (high - low) * np.sqrt(heat), 0.0)
    soot = np.clip(3.0 * heat, 0.0, 1.0)
    # Smoke: a widening column from the flame's tip, thinning out towards the top.
    smoke_radius = 0.1 + 0.25 * np.clip((z - 0.8) / 1.6, 0.0, 1.0)
    column = np.clip(1.2 - r / smoke_radius, 0.0, 1.0) * np.clip((z - 0.9) / 0.4, 0.0, 1.0)
    smoke = column * np.clip((2.35 - z) / 0.9, 0.0, 1.0) * np.clip(0.5 + 0.6 * detail, 0.0, 1.0)
    as_grid = lambda values, name: Grid(np.ascontiguousarray(values.astype(np.float32)), index_to_world, name)
    return as_grid(soot, "density"), as_grid(temperature, "temperature"), as_grid(smoke, "density")


def fire(width: int, height: int, spp: int) -> Scene:
    """A flame of black-body emitting soot with grey smoke above it, under a faint night sky."""
    soot, temperature, smoke = fire_grids()
    emission = BlackbodyEmission(temperature=temperature, intensity=FIRE_INTENSITY)
    flame = medium(soot, 5.0, name="flame", albedo=0.2, emission=emission)
    plume = medium(smoke, 6.0, name="smoke", albedo=0.7)
    # A bluish moon from above and behind lights the smoke; the background stays black.
    moon = sun(direction(45.0, 150.0), 1.0, spectrum=spectra.blackbody(MOON_TEMPERATURE), name="moon")
    cam = perspective((0.0, -4.6, 1.0), (0.0, 0.0, 1.0), width, height, 48.0)
    return scene(cam, (flame, plume), (moon,), spp=spp, seed=SEED)


# ----------------------------------------------------------------------------- a cloud over a ground plane

# A cumulus-like cloud (the procedural cloud, grey, forward scattering) floating over a grassy ground plane
# under a sun and a sky: the ground is a surface (a Diffuse BSDF in the .blend), the cloud casts its shadow
# on it, and the film is transparent (Film ▸ Transparent) where the camera sees the sky, so the render
# composites over a plate.
CLOUD_CENTRE = (0.0, 0.0, 1.5)
CLOUD_SIZE = 2.2  # the cloud's cube, world units
CLOUD_CELLS = 48
CLOUD_SEED = 3
CLOUD_DENSITY = 16.0  # σ_t per unit of the grid's density (its values are in [0, 1])
GROUND_RGB = (0.20, 0.32, 0.10)  # linear Rec.709 Base Color of the grass
GROUND_HALF = 8.0
SHADOW_SUN = (45.0, 60.0)  # elevation, azimuth: in front and to the right, so the shadow falls towards the camera
SHADOW_SKY_STRENGTH = 0.2  # the sky's radiance Y against the sun's irradiance Y of 1


def cloud_medium() -> Medium:
    grid = cloud_grid(CLOUD_CELLS, CLOUD_SIZE, CLOUD_CENTRE, seed=CLOUD_SEED)
    return medium(grid, CLOUD_DENSITY, name="cloud", albedo=0.97, g=0.6)


def ground_plane() -> Surface:
    """A square at z = 0, GROUND_HALF either side of the origin, its reflectance the smooth spectrum of
    GROUND_RGB (as the exporter turns a Base Color into one)."""
    h = GROUND_HALF
    vertices = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
    return Surface(name="ground", vertices=vertices, triangles=np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32),
                   reflectance=spectra.scaled_from_rgb(np.array(GROUND_RGB)))


def cloud_shadow(width: int, height: int, spp: int) -> Scene:
    """The cloud, its shadow on the ground, the sky seen past them (transparent: alpha 0); D65 sun and sky."""
    cam = perspective((0.0, -7.0, 2.0), (0.0, 0.0, 1.0), width, height, 45.0)
    light = sun(direction(*SHADOW_SUN), 1.0, spectrum=LIGHTS["D65"], name="sun")
    sky = environment(SHADOW_SKY_STRENGTH, spectrum=LIGHTS["D65"], name="sky")
    return scene(cam, (cloud_medium(),), (light, sky), (ground_plane(),), spp=spp, seed=SEED, transparent=True)
