"""Blender's Sky Texture evaluated as Cycles evaluates it: the sky's radiance from the node's parameters,
for an envmap light (linear Rec.709 texels), and its sun disc, for a sun light.

Two physical models, both spectral computations of light scattered in Earth's atmosphere seen from an
altitude, whose radiance Cycles turns into CIE XYZ and then into its linear Rec.709 (negative components
clamped to 0):

- "SINGLE_SCATTERING" (Nishita 1993, Blender 2.90's "Nishita"): Rayleigh and Mie (Cornette–Shanks phase, g
  0.76) single scattering and ozone absorption over 21 wavelengths, 380–780 nm, of a 5778 K black-body
  sun, marched in 32 steps along the view ray with the optical depth to the sun by an 8-node
  Gauss–Laguerre quadrature; XYZ by the CIE 1931 functions summed at those wavelengths × 20 nm.
- "MULTIPLE_SCATTERING" (García Liñán 2024, Blender 5's default): molecules, aerosols (Henyey–Greenstein g
  0.8) and ozone with measured altitude profiles, single scattering marched in 64 steps with the
  transmittance to the sun from a 256 × 64 table, plus a fitted multiple-scattering term and the light
  reflected by a ground of albedo 0.3, at four wavelengths (630, 560, 490, 430 nm) taken to XYZ by the
  model's fitted 4 × 3 matrix.

As Cycles does (`intern/sky`, `SkyTextureNode`, `svm/sky.h`), the sky is tabulated once per parameter set
on a 512 × 256 texture (azimuth × elevation warped towards the horizon, mirrored about the sun's azimuth)
and read bilinearly; the sun disc is two XYZ values (the disc's lowest and highest points, the direct
sunlight through the atmosphere over the disc's solid angle) interpolated by elevation, times the limb
darkening 1 − 0.6 (1 − √(1 − (α/α₀)²)), shown where the direction is above the Earth's horizon (and, for
single scattering, above the horizontal, below which the sky fades to black by (1 + 2.5 z)³ to z = −0.4).
Directions are Blender's world directions; the sun lies at elevation e and rotation r towards
(cos e sin r, cos e cos r, sin e) (rotation 0 is +Y, a quarter turn +X).

And one analytic fit, "PREETHAM" (Preetham, Shirley & Smits 1999): the Perez luminance distribution for Y
and the chromaticities x, y, each (1 + A e^(B / cos θ)) (1 + C e^(D γ) + E cos² γ) of the view's zenith angle
θ (held at the horizon below it) and its angle γ to the sun (*Sun Direction*), with coefficients linear in
the *Turbidity* T, scaled by the zenith values (Y's, 0.06 × the paper's kcd/m², and x's and y's cubic fits in
the sun's zenith angle), as xyY; no sun disc.
"""

from dataclasses import dataclass

import numpy as np

from . import colorimetry
from .planck import planck_radiance
from .wavelengths import LAMBDA_MIN

MODELS = ("SINGLE_SCATTERING", "MULTIPLE_SCATTERING", "PREETHAM")
TABLE_WIDTH, TABLE_HEIGHT = 512, 256  # Cycles' precomputed sky texture (azimuth × warped elevation)
MIN_SUN_SIZE = 0.0005  # radians: Cycles clamps the sun's angular diameter to at least this
LIMB_DARKENING = 0.6


@dataclass(frozen=True)
class SkyParameters:
    """A Sky Texture's settings, in Blender's units (angles in radians, altitude in metres)."""

    model: str = "MULTIPLE_SCATTERING"
    sun_elevation: float = np.radians(15.0)
    sun_rotation: float = 0.0
    altitude: float = 100.0
    air: float = 1.0
    aerosol: float = 1.0
    ozone: float = 1.0
    sun_disc: bool = True
    sun_size: float = np.radians(0.545)
    sun_intensity: float = 1.0
    sun_direction: tuple = (0.0, 0.0, 1.0)  # Preetham's sun
    turbidity: float = 2.2  # Preetham's


def _ray_sphere(origin, direction, radius):
    """Distance along unit `direction` from `origin` (..., 3) to a sphere about the centre: the exit when
    inside, the entry when outside and heading in, −1 for a miss or a sphere behind."""
    b = np.sum(origin * direction, axis=-1)
    c = np.sum(origin * origin, axis=-1) - radius * radius
    d = b * b - c
    root = np.sqrt(np.maximum(d, 0.0))
    distance = np.where(d >= b * b, -b + root, -b - root)
    return np.where((d < 0.0) | ((c > 0.0) & (b > 0.0)), -1.0, distance)


def _bilinear(table, x, y):
    """Linear interpolation of `table` (rows, columns, ...) at fractional indices x (columns), y (rows),
    clamped at the edges."""
    rows, columns = table.shape[:2]
    x = np.clip(x, 0.0, columns - 1.0)
    y = np.clip(y, 0.0, rows - 1.0)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    x1, y1 = np.minimum(x0 + 1, columns - 1), np.minimum(y0 + 1, rows - 1)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    bottom = table[y0, x0] + fx * (table[y0, x1] - table[y0, x0])
    top = table[y1, x0] + fx * (table[y1, x1] - table[y1, x0])
    return bottom + fy * (top - bottom)


class _Single:
    """Nishita single scattering, in metres and per metre."""

    EARTH, ATMOSPHERE = 6360e3, 6420e3
    RAYLEIGH_SCALE, MIE_SCALE, MIE = 8e3, 1.2e3, 2e-5  # scale heights (m), Mie scattering (m⁻¹)
    MIE_EXTINCTION = 1.11  # Mie extinction ÷ scattering
    G = 0.76
    STEPS = 32
    WAVELENGTHS = np.arange(380.0, 781.0, 20.0)
    # Solar irradiance at the top of the atmosphere (W·m⁻²·nm⁻¹): Planck's 5778 K over the solid angle the
    # model gives the sun (its table's values to 3e-7).
    IRRADIANCE = planck_radiance(WAVELENGTHS, 5778.0) * 6.7901644e-5
    # Rayleigh scattering and ozone absorption (m⁻¹ at sea level; ozone at its peak density) at WAVELENGTHS.
    RAYLEIGH = np.array([5.424820087636473e-05, 4.418549866505454e-05, 3.635151910165377e-05, 3.017929012024763e-05,
                         2.526320226989157e-05, 2.130859310621843e-05, 1.809838025320633e-05, 1.547057129129042e-05,
                         1.330284977336850e-05, 1.150184784075764e-05, 9.99557429990163e-06, 8.72799973630707e-06,
                         7.65513700977967e-06, 6.74217203751443e-06, 5.96134125832052e-06, 5.29034598065810e-06,
                         4.71115687557433e-06, 4.20910481110487e-06, 3.77218381260133e-06, 3.39051255477280e-06,
                         3.05591531679811e-06])
    OZONE = np.array([3.25126849861e-09, 5.85395365047e-09, 1.977191155085e-08, 7.309568762914e-08, 2.0084561514287e-07,
                      4.0383958096161e-07, 6.3551335912363e-07, 9.6707041180970e-07, 1.54797400424410e-06,
                      2.09038647223331e-06, 2.46128056164565e-06, 2.73551299461512e-06, 2.15125863128643e-06,
                      1.59051840791988e-06, 1.12356197979857e-06, 7.3527551487574e-07, 4.6450130357806e-07,
                      3.3096079921048e-07, 2.2512612292678e-07, 1.4879129266490e-07, 1.6828623364192e-07])
    # Gauss–Laguerre (8 nodes) for the optical depth to the sun, nodes and weights (× eˣ) scaled to a ray of
    # length 1 whose last node is inside the atmosphere.
    NODES = np.array([0.006811185292, 0.03614807107, 0.09004346519, 0.1706680068, 0.2818362161, 0.4303406404,
                      0.6296271457, 0.9145252695])
    WEIGHTS = np.array([0.01750893642, 0.04135477391, 0.06678839063, 0.09507698807, 0.1283416365, 0.1707430204,
                        0.2327233347, 0.3562490486])

    def __init__(self, parameters: SkyParameters):
        self.scale = np.array([parameters.air, parameters.aerosol, parameters.ozone])
        self.origin = np.array([0.0, 0.0, self.EARTH + np.clip(parameters.altitude, 1.0, 59999.0)])

    def densities(self, height):
        """(..., 3): the relative densities of air, aerosols and ozone at `height` metres."""
        return np.stack([np.exp(-height / self.RAYLEIGH_SCALE), np.exp(-height / self.MIE_SCALE),
                         np.maximum(0.0, 1.0 - np.abs(height - 25e3) / 15e3)], axis=-1)

    def optical_depth(self, origin, direction):
        """(..., 3): the integrals of the relative densities from `origin` along `direction` out of the
        atmosphere (metres)."""
        length = _ray_sphere(origin, direction, self.ATMOSPHERE)
        points = origin[..., None, :] + (self.NODES[:, None] * direction[..., None, :]) * length[..., None, None]
        height = np.linalg.norm(points, axis=-1) - self.EARTH
        return np.einsum("...nk,n->...k", self.densities(height), self.WEIGHTS) * length[..., None]

    def extinction(self, optical_depth, ozone=True):
        """(..., 21): optical depths at the wavelengths of relative-density integrals (..., 3), scaled."""
        depth = optical_depth * self.scale
        tau = depth[..., 0:1] * self.RAYLEIGH + depth[..., 1:2] * (self.MIE_EXTINCTION * self.MIE)
        return tau + depth[..., 2:3] * self.OZONE if ozone else tau

    def inscattering(self, directions, sun):
        """(N, 21): the radiance scattered once towards the observer along unit `directions` (N, 3)."""
        length = _ray_sphere(self.origin, directions, self.ATMOSPHERE)
        segment = (length / self.STEPS)[:, None]
        mu = directions @ sun
        g2 = self.G**2
        rayleigh_phase = 3.0 / (16.0 * np.pi) * (1.0 + mu * mu)
        mie_phase = 3.0 * (1.0 - g2) * (1.0 + mu * mu) / (8.0 * np.pi * (2.0 + g2) * (1.0 + g2 - 2.0 * self.G * mu) ** 1.5)
        depth = np.zeros((len(directions), 3))
        radiance = np.zeros((len(directions), self.WAVELENGTHS.size))
        for step in range(self.STEPS):
            points = self.origin + (step + 0.5) * segment * directions
            density = self.densities(np.linalg.norm(points, axis=-1) - self.EARTH)
            depth += segment * density
            lit = ~self.sun_below_surface(points, sun)
            attenuation = np.exp(-self.extinction(depth + self.optical_depth(points, sun)))
            scattering = ((density[:, 0] * self.scale[0] * rayleigh_phase)[:, None] * self.RAYLEIGH
                          + (density[:, 1] * self.scale[1] * mie_phase * self.MIE)[:, None])
            radiance += np.where(lit[:, None], attenuation * scattering * self.IRRADIANCE * segment, 0.0)
        return radiance

    def sun_below_surface(self, points, sun):
        """Whether the Earth hides the sun from `points`."""
        if sun[2] >= 0.0:
            return np.zeros(len(points), dtype=bool)
        b = 2.0 * (points @ sun)
        c = np.sum(points * points, axis=-1) - self.EARTH**2
        return b * b - 4.0 * c >= 0.0

    def to_xyz(self, spectra):
        """(..., 3): Cycles' XYZ of spectra at WAVELENGTHS: the CIE 1931 functions there, summed × 20 nm."""
        cmf = colorimetry.cmf("cie1931")[:, (self.WAVELENGTHS - LAMBDA_MIN).astype(int)]
        return spectra @ cmf.T * (self.WAVELENGTHS[1] - self.WAVELENGTHS[0])

    def table(self, elevation):
        """(TABLE_HEIGHT, TABLE_WIDTH, 3) XYZ: rows above the middle at latitude π/2 (y / (H/2) − 1)², the
        lower half black; column x at longitude 2π x / W − π from the sun's, the right half a mirror."""
        half_width, half_height = TABLE_WIDTH // 2, TABLE_HEIGHT // 2
        rows = np.arange(half_height + 1, TABLE_HEIGHT)
        latitude = 0.5 * np.pi * (rows / half_height - 1.0) ** 2
        longitude = 2.0 * np.pi / TABLE_WIDTH * np.arange(half_width) - np.pi
        lat, lon = np.meshgrid(latitude, longitude, indexing="ij")
        directions = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)
        sun = np.array([np.cos(elevation), 0.0, np.sin(elevation)])
        table = np.zeros((TABLE_HEIGHT, TABLE_WIDTH, 3))
        xyz = self.to_xyz(self.inscattering(directions.reshape(-1, 3), sun)).reshape(len(rows), half_width, 3)
        table[rows, :half_width] = xyz
        table[rows, half_width:] = xyz[:, ::-1]
        return table

    def sun_xyz(self, elevation, solid_angle):
        """XYZ radiance of the sun at `elevation` (no ozone: Cycles leaves it out of the sun's light)."""
        elevation = max(elevation, 0.0)
        direction = np.array([np.cos(elevation), 0.0, np.sin(elevation)])
        tau = self.extinction(self.optical_depth(self.origin, direction), ozone=False)
        return self.to_xyz(self.IRRADIANCE * np.exp(-tau) / solid_angle)


class _Multiple:
    """García Liñán's four-wavelength model with multiple scattering, in kilometres and per kilometre."""

    EARTH, THICKNESS = 6371.0, 100.0
    ATMOSPHERE = EARTH + THICKNESS
    G = 0.8
    GROUND_ALBEDO = 0.3
    STEPS = 64
    LUT_WIDTH, LUT_HEIGHT, LUT_STEPS = 256, 64, 64  # transmittance table: cos(sun zenith) × altitude
    # At 630, 560, 490, 430 nm: solar irradiance, molecular scattering at sea level, ozone and aerosol
    # cross sections; the model's fitted matrix from these four samples to XYZ (rows) and its fit of the
    # multiply scattered light.
    SUN = np.array([1.679, 1.828, 1.986, 1.307])
    MOLECULAR = np.array([6.605e-3, 1.067e-2, 1.842e-2, 3.156e-2])
    OZONE_CROSS_SECTION = np.array([3.472e-25, 3.914e-25, 1.349e-25, 11.03e-27])
    OZONE_MEAN_DOBSON = 334.5
    AEROSOL_ABSORPTION = np.array([2.8722e-24, 4.6168e-24, 7.9706e-24, 1.3578e-23])
    AEROSOL_SCATTERING = np.array([1.5908e-22, 1.7711e-22, 2.0942e-22, 2.4033e-22])
    AEROSOL_BASE, AEROSOL_BACKGROUND, AEROSOL_SCALE = 1.3681e20, 2e6, 0.73
    TO_XYZ = np.array([[53.386917738564668023, 22.981337506691024754, 0.0],
                       [43.904844466369358263, 71.347795700053393866, 0.102506867965741307],
                       [1.6137278251608962005, 18.422960591455485011, 31.742921188390805758],
                       [20.762668673810577145, 2.3614213523314368527, 110.48009643252140334]])
    MULTIPLE = 0.02 * np.array([0.217, 0.347, 0.594, 1.0])

    def __init__(self, parameters: SkyParameters):
        self.air, self.aerosol, self.ozone = parameters.air, parameters.aerosol, parameters.ozone
        self.altitude = np.clip(parameters.altitude, 1.0, 99999.0) / 1000.0
        self.lut = None

    def coefficients(self, altitude):
        """(extinction, molecular scattering, aerosol scattering), each (..., 4), at `altitude` km."""
        aerosol = self.AEROSOL_BASE * (np.exp(-altitude / self.AEROSOL_SCALE)
                                       + self.AEROSOL_BACKGROUND / self.AEROSOL_BASE) * self.aerosol
        log_h = np.log(np.maximum(altitude, 1e-4))
        ozone = 3.78547397e20 * np.exp(-(log_h - 3.22261) ** 2 * 5.55555555 - log_h)
        molecular = self.MOLECULAR * (np.exp(-0.07771971 * altitude**1.16364243) * self.air)[..., None]
        aerosol_scattering = self.AEROSOL_SCATTERING * aerosol[..., None]
        absorption = (self.AEROSOL_ABSORPTION * aerosol[..., None]
                      + self.OZONE_CROSS_SECTION * self.OZONE_MEAN_DOBSON * (ozone * self.ozone)[..., None])
        return absorption + aerosol_scattering + molecular, molecular, aerosol_scattering

    def transmittance(self, cos_zenith, normalised_altitude):
        """(..., 4): the transmittance to the top of the atmosphere towards a sun at `cos_zenith`, from a
        height `normalised_altitude` × the atmosphere's thickness (the Earth does not block it)."""
        cos_zenith, normalised_altitude = np.broadcast_arrays(np.asarray(cos_zenith, float),
                                                              np.asarray(normalised_altitude, float))
        sun = _sun_direction(cos_zenith)
        origin = np.zeros(cos_zenith.shape + (3,))
        origin[..., 2] = self.EARTH + normalised_altitude * self.THICKNESS
        step = _ray_sphere(origin, sun, self.ATMOSPHERE) / self.LUT_STEPS
        depth = np.zeros(cos_zenith.shape + (4,))
        for index in range(self.LUT_STEPS):
            points = origin + ((index + 0.5) * step)[..., None] * sun
            altitude = np.maximum(np.linalg.norm(points, axis=-1) - self.EARTH, 0.0)
            depth += self.coefficients(altitude)[0] * step[..., None]
        return np.exp(-depth)

    def precompute(self):
        """Tabulate the transmittance to the sun (the model's 256 × 64 table, read bilinearly)."""
        u = np.arange(self.LUT_WIDTH) / (self.LUT_WIDTH - 1.0)
        v = np.arange(self.LUT_HEIGHT) / (self.LUT_HEIGHT - 1.0)
        self.lut = self.transmittance(2.0 * u[None, :] - 1.0, v[:, None])

    def lookup(self, cos_zenith, normalised_altitude):
        x = (self.LUT_WIDTH - 1.0) * np.clip(cos_zenith * 0.5 + 0.5, 0.0, 1.0)
        y = (self.LUT_HEIGHT - 1.0) * np.clip(normalised_altitude, 0.0, 1.0)
        return _bilinear(self.lut, x, y)

    def multiple_scattering(self, cos_zenith, normalised_altitude, distance):
        """(..., 4): the fitted multiply scattered light and the sunlight reflected once by the ground."""
        planet = 2.0 * np.pi * (1.0 - np.sqrt(np.maximum(1.0 - (self.EARTH / distance) ** 2, 0.0)))
        to_ground = self.lookup(cos_zenith, 0.0)
        ground_to_point = self.lookup(1.0, 0.0) / self.lookup(1.0, normalised_altitude)
        ground = ((planet * cos_zenith / (4.0 * np.pi) * self.GROUND_ALBEDO / np.pi)[..., None]
                  * to_ground * ground_to_point)
        fit = self.MULTIPLE * (1.0 / (1.0 + 5.0 * np.exp(-17.92 * cos_zenith)))[..., None]
        return fit + ground

    def inscattering(self, directions, sun):
        """(N, 4): the radiance scattered towards the observer along unit `directions` (N, 3) up to the
        ground or the top of the atmosphere."""
        origin = np.array([0.0, 0.0, self.EARTH + self.altitude])
        ground = _ray_sphere(origin, directions, self.EARTH)
        length = np.where(ground < 0.0, _ray_sphere(origin, directions, self.ATMOSPHERE), ground)
        step = length / self.STEPS
        cos_theta = -(directions @ sun)
        molecular_phase = 3.0 / (16.0 * np.pi) * (1.0 + cos_theta**2)
        den = 1.0 + self.G**2 + 2.0 * self.G * cos_theta
        aerosol_phase = (1.0 - self.G**2) / (4.0 * np.pi * den * np.sqrt(den))
        radiance = np.zeros((len(directions), 4))
        transmittance = np.ones((len(directions), 4))
        for index in range(self.STEPS):
            points = origin + ((index + 0.5) * step)[:, None] * directions
            distance = np.linalg.norm(points, axis=-1)
            altitude = np.maximum(distance - self.EARTH, 0.0)
            normalised = altitude / self.THICKNESS
            cos_zenith = (points @ sun) / distance
            extinction, molecular, aerosol = self.coefficients(altitude)
            to_sun = self.lookup(cos_zenith, normalised)
            scattered = self.multiple_scattering(cos_zenith, normalised, distance)
            source = self.SUN * (molecular * (molecular_phase[:, None] * to_sun + scattered)
                                 + aerosol * (aerosol_phase[:, None] * to_sun + scattered))
            step_transmittance = np.exp(-step[:, None] * extinction)
            radiance += transmittance * source * (1.0 - step_transmittance) / np.maximum(extinction, 1e-7)
            transmittance *= step_transmittance
        return radiance

    def table(self, elevation):
        """(TABLE_HEIGHT, TABLE_WIDTH, 3) XYZ at texel centres: azimuth 2π u from the anti-sun's, elevation
        sign(l) l² π/2 with l = 2 v − 1; the right half a mirror."""
        if self.lut is None:
            self.precompute()
        half_width = TABLE_WIDTH // 2
        azimuth = 2.0 * np.pi * (np.arange(half_width) + 0.5) / TABLE_WIDTH
        l = 2.0 * (np.arange(TABLE_HEIGHT) + 0.5) / TABLE_HEIGHT - 1.0
        elev = np.sign(l) * l * l * (0.5 * np.pi)
        el, az = np.meshgrid(elev, azimuth, indexing="ij")
        directions = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)
        sun = _sun_direction(np.sin(elevation))
        xyz = (self.inscattering(directions.reshape(-1, 3), sun) @ self.TO_XYZ).reshape(TABLE_HEIGHT, half_width, 3)
        return np.concatenate([xyz, xyz[:, ::-1]], axis=1)

    def sun_xyz(self, elevation, solid_angle):
        transmittance = self.transmittance(np.sin(elevation), self.altitude / self.THICKNESS)
        return (self.SUN * transmittance / solid_angle) @ self.TO_XYZ


class _Preetham:
    """The Preetham sky: Perez functions of the view's zenith angle and its angle to the sun, in xyY."""

    # Perez coefficients A–E of Y, x and y: (slope in T, intercept).
    PEREZ = np.array([[(0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)],
                      [(-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)],
                      [(-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)]])
    # Zenith chromaticities x and y: rows T², T, 1; columns θs³, θs², θs, 1.
    ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394],
                         [0.11693, -0.21196, 0.06052, 0.25886]])
    ZENITH_Y = np.array([[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516],
                         [0.15346, -0.26756, 0.06670, 0.26688]])

    def __init__(self, parameters: SkyParameters):
        sun = np.asarray(parameters.sun_direction, dtype=np.float64)
        self.theta, self.phi = np.arccos(np.clip(sun[2], -1.0, 1.0)), np.arctan2(sun[0], sun[1])
        t = parameters.turbidity
        self.perez = self.PEREZ[..., 0] * t + self.PEREZ[..., 1]
        chi = (4.0 / 9.0 - t / 120.0) * (np.pi - 2.0 * self.theta)
        powers = self.theta ** np.arange(3, -1, -1)
        zenith = np.array([0.06 * ((4.0453 * t - 4.9710) * np.tan(chi) - 0.2155 * t + 2.4192),
                           np.array([t * t, t, 1.0]) @ self.ZENITH_X @ powers,
                           np.array([t * t, t, 1.0]) @ self.ZENITH_Y @ powers])
        self.zenith = zenith / self._perez(0.0, self.theta)

    def _perez(self, theta, gamma):
        """(..., 3): the Perez function of Y, x and y."""
        a, b, c, d, e = (self.perez[:, index] for index in range(5))
        theta, gamma = np.asarray(theta)[..., None], np.asarray(gamma)[..., None]
        return (1.0 + a * np.exp(b / np.cos(theta))) * (1.0 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)

    def xyz(self, directions):
        d = np.asarray(directions, dtype=np.float64)
        theta, phi = np.arccos(np.clip(d[..., 2], -1.0, 1.0)), np.arctan2(d[..., 0], d[..., 1])
        cos_gamma = (np.sin(self.theta) * np.sin(theta) * np.cos(phi - self.phi)
                     + np.cos(self.theta) * np.cos(theta))
        gamma = np.arccos(np.clip(cos_gamma, -1.0, 1.0))
        luminance, x, y = np.moveaxis(self.zenith * self._perez(np.minimum(theta, 0.5 * np.pi - 0.001), gamma), -1, 0)
        safe_y = np.where(y != 0.0, y, 1.0)
        return np.stack([np.where(y != 0.0, x / safe_y * luminance, 0.0), luminance,
                         np.where((y != 0.0) & (luminance != 0.0), (1.0 - x - y) / safe_y * luminance, 0.0)], axis=-1)


def _sun_direction(cos_zenith):
    """The model's sun direction (towards −X) at `cos_zenith`, (..., 3)."""
    cos_zenith = np.asarray(cos_zenith, dtype=np.float64)
    return np.stack([-np.sqrt(np.maximum(1.0 - cos_zenith**2, 0.0)), np.zeros_like(cos_zenith), cos_zenith], axis=-1)


def wrapped_sun(elevation: float, rotation: float) -> tuple[float, float]:
    """Cycles' sun position: the elevation wrapped into [−π/2, π/2] (past the zenith the sun continues on
    the other side, half a turn round) and the rotation into [0, 2π)."""
    elevation = np.fmod(elevation, 2.0 * np.pi)
    if abs(elevation) >= np.pi:
        elevation -= np.copysign(2.0 * np.pi, elevation)
    if abs(elevation) >= 0.5 * np.pi:
        elevation = np.copysign(np.pi, elevation) - elevation
        rotation += np.pi
    return float(elevation), float(np.mod(rotation, 2.0 * np.pi))


def sun_direction(parameters: SkyParameters) -> np.ndarray:
    """The unit world direction towards the sun's centre."""
    elevation, rotation = wrapped_sun(parameters.sun_elevation, parameters.sun_rotation)
    return np.array([np.cos(elevation) * np.sin(rotation), np.cos(elevation) * np.cos(rotation), np.sin(elevation)])


class Sky:
    """One Sky Texture's sky (tabulated, or Preetham's closed form) and sun disc (none for Preetham): the node's
    output along a direction is `sky_rgb` + `sun_rgb`."""

    def __init__(self, parameters: SkyParameters):
        if parameters.model not in MODELS:
            raise ValueError(f"unknown sky model {parameters.model!r}; choose one of {', '.join(MODELS)}")
        self.parameters = parameters
        self.elevation, rotation = wrapped_sun(parameters.sun_elevation, parameters.sun_rotation)
        self.table_rotation = 2.0 * np.pi - rotation  # the lookup's offset of the sun's azimuth
        self.sun = sun_direction(parameters)
        self.single = parameters.model == "SINGLE_SCATTERING"
        self.preetham = _Preetham(parameters) if parameters.model == "PREETHAM" else None
        self.sun_size = max(parameters.sun_size, MIN_SUN_SIZE)
        self.sun_bottom = self.sun_top = np.zeros(3)
        if self.preetham is None:
            model = _Single(parameters) if self.single else _Multiple(parameters)
            self.table = model.table(self.elevation)
            solid_angle = 2.0 * np.pi * (1.0 - np.cos(0.5 * self.sun_size))
            self.sun_bottom, self.sun_top = (model.sun_xyz(self.elevation + sign * 0.5 * self.sun_size, solid_angle)
                                             for sign in (-1.0, 1.0))
        if self.single and self.elevation + 0.5 * self.sun_size <= 0.0:  # set: Cycles shows no disc
            self.sun_bottom = self.sun_top = np.zeros(3)
        # Below this elevation the Earth hides the sun (Cycles' altitude unclamped, the multiple model's Earth).
        self.horizon = -(0.5 * np.pi - np.arcsin(_Multiple.EARTH / (_Multiple.EARTH + parameters.altitude / 1000.0)))

    def sky_xyz(self, directions) -> np.ndarray:
        """(..., 3): the sky without the sun disc along unit world `directions` (..., 3)."""
        if self.preetham is not None:
            return self.preetham.xyz(directions)
        d = np.asarray(directions, dtype=np.float64)
        elevation = np.arcsin(np.clip(d[..., 2], -1.0, 1.0))
        u = np.mod((-np.arctan2(d[..., 1], d[..., 0]) - 0.5 * np.pi + self.table_rotation) / (2.0 * np.pi), 1.0)
        v = np.sqrt(np.abs(elevation) / (0.5 * np.pi)) * np.sign(elevation) * 0.5 + 0.5
        if self.single:  # below the horizontal: the horizon's row, fading to black at z = −0.4
            v = np.where(d[..., 2] < 0.0, 0.508, v)
        xyz = _bilinear(self.table, u * TABLE_WIDTH - 0.5, v * TABLE_HEIGHT - 0.5)
        if self.single:
            fade = np.where(d[..., 2] < 0.0, np.maximum(1.0 + 2.5 * d[..., 2], 0.0) ** 3, 1.0)
            xyz = xyz * fade[..., None]
        return xyz

    def sun_rgb(self, directions) -> np.ndarray:
        """(..., 3): the sun disc's linear Rec.709 (clamped at 0, times Sun Intensity) along unit world
        `directions`, 0 off the disc."""
        d = np.asarray(directions, dtype=np.float64)
        half = 0.5 * self.sun_size
        angle = np.arccos(np.clip(d @ self.sun, -1.0, 1.0))
        elevation = np.arcsin(np.clip(d[..., 2], -1.0, 1.0))
        y = ((elevation - self.elevation) / self.sun_size + 0.5)[..., None]
        rgb = _rgb(self.sun_bottom + y * (self.sun_top - self.sun_bottom))
        limb = 1.0 - LIMB_DARKENING * (1.0 - np.sqrt(np.maximum(1.0 - (angle / half) ** 2, 0.0)))
        shown = (angle < half) & (elevation > self.horizon) & self.parameters.sun_disc
        if self.single:
            shown &= d[..., 2] >= 0.0
        return np.where(shown[..., None], rgb * (limb * self.parameters.sun_intensity)[..., None], 0.0)

    def sky_rgb(self, directions) -> np.ndarray:
        """(..., 3): the sky's linear Rec.709 (clamped at 0) without the sun disc."""
        return _rgb(self.sky_xyz(directions))

    def sky_map(self, width: int) -> np.ndarray:
        """(width / 2, width, 3) float32: the sky's linear Rec.709 at the texel centres of an equirectangular
        envmap of the world (the `Light` envmap's mapping: +X at the centre column, +Z the top row)."""
        height = width // 2
        polar = np.pi * (np.arange(height) + 0.5) / height
        azimuth = np.pi * (1.0 - 2.0 * (np.arange(width) + 0.5) / width)
        p, a = np.meshgrid(polar, azimuth, indexing="ij")
        directions = np.stack([np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)], axis=-1)
        return self.sky_rgb(directions).astype(np.float32)

    def sun_irradiance_rgb(self, nodes: int = 48) -> np.ndarray:
        """(3,): the sun disc's irradiance on a plane facing it, ∫ rgb cos dω over the disc, by Gauss–Legendre
        quadrature in the angle from its centre and the midpoint rule around it."""
        half = 0.5 * self.sun_size
        x, w = np.polynomial.legendre.leggauss(nodes)
        angle, angle_weight = 0.5 * half * (x + 1.0), 0.5 * half * w
        turn = 2.0 * np.pi * (np.arange(2 * nodes) + 0.5) / (2 * nodes)
        helper = np.array([0.0, 0.0, 1.0]) if abs(self.sun[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        e1 = np.cross(self.sun, helper)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(self.sun, e1)
        a, t = np.meshgrid(angle, turn, indexing="ij")
        directions = (np.cos(a)[..., None] * self.sun + np.sin(a)[..., None]
                      * (np.cos(t)[..., None] * e1 + np.sin(t)[..., None] * e2))
        weight = (angle_weight * np.sin(angle) * np.cos(angle))[:, None] * (2.0 * np.pi / turn.size)
        return np.einsum("ij,ijk->k", weight, self.sun_rgb(directions))


def _rgb(xyz) -> np.ndarray:
    """Cycles' linear Rec.709 of XYZ, negative components clamped to 0."""
    return np.maximum(colorimetry.xyz_to_rgb(xyz), 0.0)
