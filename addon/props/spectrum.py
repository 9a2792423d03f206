"""Spectrum settings: where a spectrum comes from (preset, blackbody, band, colour, curve, CSV file).

One PropertyGroup per role, because each role offers its own sources and defaults and previews
differently: a light's colour, a reflectance under D65, the colour transmitted through an absorber.
`spectrum_values.to_spectrum` turns any of them into a tracer Spectrum.
"""

import bpy

from . import curves
from .curves import SpectralCurve
from .swatch import preview_colour
from ..tracer.spectra import BANDS, ILLUMINANT_NAMES, RGB_METHODS
from ..tracer.wavelengths import LAMBDA_MAX, LAMBDA_MIN

SOURCES = {
    "CONSTANT": ("Constant", "The same value at every wavelength"),
    "ILLUMINANT": ("Preset", "A CIE standard illuminant: daylight, tungsten, fluorescent lamps, LEDs"),
    "BLACKBODY": ("Blackbody", "A black body's spectrum at a temperature"),
    "BAND": ("Band", "A named narrow band (a lamp or laser line)"),
    "GAUSSIAN": ("Peak", "A Gaussian peak of a given center and width"),
    "COLOR": ("Color", "A smooth spectrum with this RGB color (Jakob–Hanika 2019 or Otsu 2018 recovery)"),
    "CURVE": ("Curve", "Drawn in a curve editor, wavelength along x"),
    "CSV": ("CSV File", "Imported from a file of wavelength, value rows"),
}
CSV_UNIT_ITEMS = [("nm", "nm", "Nanometres"), ("um", "µm", "Micrometres"), ("A", "Å", "Ångström")]
ILLUMINANT_LABELS = {"E": "E (equal energy)", "A": "A (tungsten)", "D65": "D65 (daylight)", "D50": "D50 (horizon)"}


def _items(keys, table):
    return [(key, table[key][0], table[key][1]) for key in keys]


def _illuminant_items():
    return [(name, ILLUMINANT_LABELS.get(name, name), f"CIE illuminant {name}") for name in ILLUMINANT_NAMES]


def _source_changed(self, _context):
    if self.source == "CURVE":
        curves.ensure(self.curve, self.Y_RANGE, values=(self.CURVE_DEFAULT, self.CURVE_DEFAULT))


def _preview(self):
    return preview_colour(self)


def _source(keys, default):
    return bpy.props.EnumProperty(name="Source", description="Where the spectrum comes from",
                                  items=_items(keys, SOURCES), default=default, update=_source_changed)


class SpectrumFields:
    """Fields every spectrum role shares; the roles add `source` and `value` with their own choices."""

    ROLE = "reflectance"  # how the swatch shows it: "light", "reflectance", "absorption" or "" (none)
    Y_RANGE = (0.0, 1.0)
    CURVE_DEFAULT = 1.0

    illuminant: bpy.props.EnumProperty(name="Preset", description="CIE standard illuminant",
                                       items=_illuminant_items(), default="D65")
    temperature: bpy.props.FloatProperty(name="Temperature", description="Black body temperature",
                                         default=5500.0, min=100.0, soft_min=800.0, soft_max=12000.0,
                                         subtype="TEMPERATURE", unit="TEMPERATURE")
    band: bpy.props.EnumProperty(name="Band", description="A named narrow band",
                                 items=[(k, v[0], f"{v[1]:g} nm ± {v[2]:g} nm") for k, v in BANDS.items()],
                                 default="UV365")
    peak: bpy.props.FloatProperty(name="Peak", description="Center wavelength (nm)", default=520.0,
                                  min=LAMBDA_MIN, max=LAMBDA_MAX)
    width: bpy.props.FloatProperty(name="Width", description="Standard deviation of the peak (nm)",
                                   default=20.0, min=0.5, soft_max=200.0)
    color: bpy.props.FloatVectorProperty(name="Color", description="Linear Rec.709 color to match",
                                         subtype="COLOR", size=3, min=0.0, max=1.0, default=(0.8, 0.8, 0.8))
    rgb_method: bpy.props.EnumProperty(name="Method", description="RGB to spectrum recovery",
                                       items=[(k, v, f"colour-science's {v} recovery") for k, v in RGB_METHODS.items()],
                                       default="jakob2019")
    curve: bpy.props.PointerProperty(type=SpectralCurve, name="Curve",
                                     description="The curve this spectrum is drawn with (Curve source)")
    filepath: bpy.props.StringProperty(name="File", description="CSV file: wavelength, value per row",
                                       subtype="FILE_PATH", options={"PATH_SUPPORTS_BLEND_RELATIVE"})
    units: bpy.props.EnumProperty(name="Units", description="Wavelength unit of the CSV file",
                                  items=CSV_UNIT_ITEMS, default="nm")
    preview: bpy.props.FloatVectorProperty(name="Preview", description="Color of this spectrum",
                                           subtype="COLOR", size=3, get=_preview)

    def set_curve_points(self, points) -> None:
        """Make this spectrum's curve run through `points`, (nm, value) pairs (presets store curves so)."""
        if len(points) < 2:
            raise ValueError(f"a spectrum curve needs at least two (nm, value) points, got {len(points)}")
        curves.set_points(curves.ensure(self.curve, self.Y_RANGE), *zip(*points))


class SpectralLightSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """The shape of a light's spectrum; its brightness is the light's own Power or Strength."""

    ROLE = "light"
    source: _source(("ILLUMINANT", "BLACKBODY", "BAND", "GAUSSIAN", "COLOR", "CURVE", "CSV"), "ILLUMINANT")
    use_window: bpy.props.BoolProperty(name="Wavelength Window",
                                       description="Keep only the wavelengths between Min and Max")
    window_min: bpy.props.FloatProperty(name="Min", description="Shortest wavelength kept (nm)", default=380.0,
                                        min=LAMBDA_MIN, max=LAMBDA_MAX)
    window_max: bpy.props.FloatProperty(name="Max", description="Longest wavelength kept (nm)", default=780.0,
                                        min=LAMBDA_MIN, max=LAMBDA_MAX)


class SpectralAlbedoSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """Single-scattering albedo over wavelength, in [0, 1]."""

    ROLE = "reflectance"
    CURVE_DEFAULT = 0.9
    source: _source(("CONSTANT", "COLOR", "CURVE", "CSV"), "CONSTANT")
    value: bpy.props.FloatProperty(name="Albedo", description="Scattered fraction of the extinction",
                                   default=0.9, min=0.0, max=1.0, subtype="FACTOR")


class SpectralReflectanceSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """A surface's diffuse reflectance over wavelength, in [0, 1]."""

    ROLE = "reflectance"
    CURVE_DEFAULT = 0.8
    source: _source(("CONSTANT", "COLOR", "CURVE", "CSV"), "CONSTANT")
    value: bpy.props.FloatProperty(name="Reflectance", description="Diffusely reflected fraction of the light",
                                   default=0.8, min=0.0, max=1.0, subtype="FACTOR")


class SpectralExtinctionSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """Extinction per unit density and metre over wavelength (multiplied by the density scale; the scene's
    Unit Scale says how many metres a Blender unit is)."""

    ROLE = "absorption"
    source: _source(("CONSTANT", "CURVE", "CSV"), "CONSTANT")
    value: bpy.props.FloatProperty(name="Extinction", description="Extinction per unit density and metre",
                                   default=1.0, min=0.0, soft_max=10.0)


class SpectralAnisotropySpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """Henyey–Greenstein g over wavelength: 0 isotropic, > 0 forward, < 0 backward scattering."""

    ROLE = ""
    Y_RANGE = (-0.99, 0.99)
    CURVE_DEFAULT = 0.0
    source: _source(("CONSTANT", "CURVE", "CSV"), "CONSTANT")
    value: bpy.props.FloatProperty(name="Anisotropy", description="Mean cosine of the scattering angle",
                                   default=0.0, min=-0.99, max=0.99, subtype="FACTOR")


class SpectralExcitationSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """How strongly a fluorophore absorbs each wavelength, per unit density."""

    ROLE = "absorption"
    source: _source(("BAND", "GAUSSIAN", "CURVE", "CSV"), "BAND")
    value: bpy.props.FloatProperty(name="Strength", default=1.0, min=0.0, soft_max=10.0,
                                   description="Absorption at the band's peak, per unit density and metre")


class SpectralEmissionSpectrum(SpectrumFields, bpy.types.PropertyGroup):
    """The colour a fluorophore re-emits (a shape: it is normalised)."""

    ROLE = "light"
    source: _source(("GAUSSIAN", "CURVE", "CSV"), "GAUSSIAN")


CLASSES = (SpectralLightSpectrum, SpectralAlbedoSpectrum, SpectralReflectanceSpectrum, SpectralExtinctionSpectrum,
           SpectralAnisotropySpectrum, SpectralExcitationSpectrum, SpectralEmissionSpectrum)
