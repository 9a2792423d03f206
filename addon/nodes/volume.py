"""A material's volume node tree → the closures Cycles would build from it, as spectra.

The meaning of every input is Cycles' own (`kernel/svm/closure.h`): per unit of density,
- Principled Volume: scattering σ_s = Color, absorption σ_a = max(1 − Color, 0)·max(1 − √Absorption Color,
  0), both times Density (× the Density Attribute's grid where the volume has it), Henyey–Greenstein of
  Anisotropy; emission Emission Strength × Emission Color and a black body of Blackbody Intensity at
  Temperature (× the Temperature Attribute's grid where the volume has it), tinted; emission is not
  multiplied by the density;
- Volume Scatter: σ_s = σ_t = Color × Density, its phase function; Volume Absorption: σ_a = (1 − Color) ×
  Density; Volume Coefficients: σ_s, σ_a and emission from its three coefficient colours;
- Emission: Color × Strength; Add Shader adds, Mix Shader weighs by (1 − Fac, Fac).
A Density (or Strength) input fed by an Attribute node reads that grid ("not found" renders nothing, as
in Cycles). Colours become spectra by `tracer.spectra` (smooth reflectances; emission colours under
D65 of luminance 1), black bodies keep Planck's shape. A phase function the tracer does not have
(Fournier–Forand, Draine, Mie) renders as Henyey–Greenstein of the node's Anisotropy, noted.
"""

from dataclasses import dataclass

import numpy as np

from ..tracer.phase import HG_G_LIMIT
from .notes import Notes
from .graph import Attribute, colour, emission_spectrum, number, output_source, reflectance_spectrum, source

CYCLES_BLACKBODY_SCALE = 1e-6  # Cycles' Principled Volume: black-body radiance σT⁴/π is scaled by 1e-6
PHASES = {"HENYEY_GREENSTEIN": "hg", "RAYLEIGH": "rayleigh"}
REGION = None  # a part's `grid` when it fills the whole volume (no attribute)


@dataclass(frozen=True)
class Scattering:
    """Scattering and absorption per unit of `grid` (an attribute name, or REGION: uniform in the volume)."""

    grid: str | None
    scattering: np.ndarray  # σ_s per unit density, on the wavelength grid
    absorption: np.ndarray  # σ_a per unit density
    phase: str
    anisotropy: float


@dataclass(frozen=True)
class Glow:
    """Emission per unit length, independent of absorption, over the volume's region or `grid`:
    `spectrum` plus `blackbody` (already with Cycles' 1e-6) × `tint` × a black body of luminance σT⁴/π at
    T = `temperature` (× the grid `temperature_grid` where it exists)."""

    grid: str | None
    spectrum: np.ndarray
    blackbody: float
    tint: np.ndarray
    temperature: float
    temperature_grid: str | None


def _reflectance(value) -> np.ndarray:
    return reflectance_spectrum(value).values


def _emission(value) -> np.ndarray:
    return emission_spectrum(value).values


def _density(node, name, owner, notes, weight, has_grid):
    """(factor, grid) of a density-like input times `weight`; (0, None) where an attribute is missing."""
    value = number(node, name, owner, notes, attribute=True)
    if isinstance(value, Attribute):
        if not has_grid(value.name):
            notes.add(f"{owner} ▸ {node.name} ▸ {name}: attribute {value.name!r} is not a grid of this volume, "
                      "so it is 0 (as in Cycles)")
            return 0.0, REGION
        return weight, value.name
    return weight * max(value, 0.0), REGION


def _phase(node, owner, notes) -> tuple[str, float]:
    kind = getattr(node, "phase", "HENYEY_GREENSTEIN")
    g = float(number(node, "Anisotropy", owner, notes)) if "Anisotropy" in node.inputs else 0.0
    if kind not in PHASES:
        notes.add(f"{owner} ▸ {node.name}: phase {kind.replace('_', ' ').title()} rendered as Henyey–Greenstein "
                  f"(g = {g:g})")
    if abs(g) > HG_G_LIMIT:
        notes.add(f"{owner} ▸ {node.name}: anisotropy {g:g} limited to ±{HG_G_LIMIT}")
        g = float(np.clip(g, -HG_G_LIMIT, HG_G_LIMIT))
    return PHASES.get(kind, "hg"), g


def _principled(node, owner, notes, weight, has_grid, parts):
    density, grid = _density(node, "Density", owner, notes, weight, has_grid)
    if density > 0:
        attribute = str(node.inputs["Density Attribute"].default_value).strip()
        if grid is REGION and attribute and has_grid(attribute):
            grid = attribute
        if str(node.inputs["Color Attribute"].default_value).strip():
            notes.add(f"{owner} ▸ {node.name} ▸ Color Attribute: per-voxel colour is not rendered (the Color is used)")
        colour_spectrum = np.minimum(_reflectance(colour(node, "Color", owner, notes)), 1.0)
        absorption_colour = np.sqrt(np.maximum(colour(node, "Absorption Color", owner, notes), 0.0))
        absorption = np.maximum(1.0 - colour_spectrum, 0.0) * np.maximum(1.0 - _reflectance(absorption_colour), 0.0)
        _hg, g = _phase(node, owner, notes)
        parts.append(Scattering(grid, density * colour_spectrum, density * absorption, "hg", g))
    strength = max(float(number(node, "Emission Strength", owner, notes)), 0.0)
    blackbody = max(float(number(node, "Blackbody Intensity", owner, notes)), 0.0)
    if strength > 0 or blackbody > 0:
        temperature_attribute = str(node.inputs["Temperature Attribute"].default_value).strip()
        tint = colour(node, "Blackbody Tint", owner, notes)
        parts.append(Glow(REGION, weight * strength * _emission(colour(node, "Emission Color", owner, notes)),
                          weight * blackbody * CYCLES_BLACKBODY_SCALE, _reflectance(tint),
                          max(float(number(node, "Temperature", owner, notes)), 0.0),
                          temperature_attribute if temperature_attribute and has_grid(temperature_attribute)
                          else None))


def _closure(node, owner, notes, weight, has_grid, parts):
    kind = node.bl_idname
    if kind == "ShaderNodeVolumePrincipled":
        _principled(node, owner, notes, weight, has_grid, parts)
    elif kind in ("ShaderNodeVolumeScatter", "ShaderNodeVolumeAbsorption"):
        density, grid = _density(node, "Density", owner, notes, weight, has_grid)
        if density > 0:
            tint = _reflectance(colour(node, "Color", owner, notes))
            if kind == "ShaderNodeVolumeScatter":
                phase, g = _phase(node, owner, notes)
                parts.append(Scattering(grid, density * tint, np.zeros_like(tint), phase, g))
            else:
                parts.append(Scattering(grid, np.zeros_like(tint), density * np.maximum(1.0 - tint, 0.0), "hg", 0.0))
    elif kind == "ShaderNodeVolumeCoefficients":
        scattering = _reflectance(colour(node, "Scatter Coefficients", owner, notes)) * weight
        absorption = _reflectance(colour(node, "Absorption Coefficients", owner, notes)) * weight
        phase, g = _phase(node, owner, notes)
        parts.append(Scattering(REGION, scattering, absorption, phase, g))
        emission = weight * _emission(colour(node, "Emission Coefficients", owner, notes))
        if emission.any():
            parts.append(Glow(REGION, emission, 0.0, np.ones_like(emission), 0.0, None))
    elif kind == "ShaderNodeEmission":
        strength, grid = _density(node, "Strength", owner, notes, weight, has_grid)
        if strength > 0:
            emission = strength * _emission(colour(node, "Color", owner, notes))
            parts.append(Glow(grid, emission, 0.0, np.ones_like(emission), 0.0, None))
    elif kind == "ShaderNodeAddShader":
        for socket in node.inputs:
            _follow(socket, owner, notes, weight, has_grid, parts)
    elif kind == "ShaderNodeMixShader":
        fac = float(np.clip(number(node, "Fac", owner, notes), 0.0, 1.0))
        _follow(node.inputs[1], owner, notes, weight * (1.0 - fac), has_grid, parts)
        _follow(node.inputs[2], owner, notes, weight * fac, has_grid, parts)
    else:
        notes.add(f"{owner} ▸ {node.name}: {node.bl_label or kind} is not a volume shader the exporter converts: "
                  "not rendered")


def _follow(socket, owner, notes, weight, has_grid, parts):
    found = source(socket)
    if found is not None and weight > 0:
        _closure(found[0], owner, notes, weight, has_grid, parts)


def has_volume_shader(material) -> bool:
    return output_source(material.node_tree, "Volume") is not None


def read_volume_shader(material, has_grid, notes: Notes) -> list:
    """The weighted Scattering and Glow parts of the material's volume shader; `has_grid(name)` says whether
    the volume has an attribute grid of that name."""
    parts = []
    found = output_source(material.node_tree, "Volume")
    if found is not None:
        _closure(found[0], f"material {material.name!r}", notes, 1.0, has_grid, parts)
    return parts
