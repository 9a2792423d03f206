"""A material's surface node tree → what an opaque Lambertian surface of the tracer can render of it.

The tracer's surfaces reflect diffusely and may emit (`tracer.scene.Surface`). From Cycles' closures:
- Diffuse BSDF: its Color is the albedo (a Roughness above 0, Oren–Nayar in Cycles, renders as Lambert,
  noted);
- either's albedo may be an Image Texture through UVs (`graph.image_texture`) where that closure is the material's
  only albedo (`SurfaceLook.texture`; mixed with other albedos, the socket's value, noted);
- Principled BSDF: its Base Color is the albedo, and Emission Color × Emission Strength its emission; its
  specular layer, and Metallic, Transmission, Coat, Sheen and Subsurface where their weights are above 0,
  are not rendered (noted, once per material);
- Emission: Color × Strength, emitted on both sides as in Cycles (shadeless: a camera sees the colour);
- Holdout: a hole for camera rays (`tracer.scene.Surface.holdout`), black (no reflectance, no emission) for
  rays after a scattering, as Cycles' holdout closure; mixed with other closures, Cycles cuts a partial hole,
  which the tracer renders as a whole one (noted);
- Add Shader adds, Mix Shader weighs by (1 − Fac, Fac); any other BSDF renders as a diffuse surface of its
  Color (noted).
A material with nothing linked to its Surface is see-through in Cycles (a volume's box): `None`. An empty
material slot is Cycles' default surface, a diffuse grey of 0.8.
Colours become spectra as in the volumes (`graph.reflectance_spectrum`, `graph.emission_spectrum`).
"""

from dataclasses import dataclass

import numpy as np

from ..tracer.wavelengths import GRID
from .graph import (ImageTexture, colour, emission_spectrum, finite, image_texture, number, output_source,
                    reflectance_spectrum, source)
from .notes import Notes

DEFAULT_ALBEDO = 0.8  # Cycles' surface of an object without a material
# Principled BSDF inputs whose closure is not rendered when their weight is above 0.
_PRINCIPLED_LAYERS = (("Metallic", "metallic"), ("Transmission Weight", "transmission"), ("Coat Weight", "coat"),
                      ("Sheen Weight", "sheen"), ("Subsurface Weight", "subsurface"))
# Colour input of each BSDF rendered as diffuse.
_COLOURED = {"ShaderNodeBsdfGlossy": "Color", "ShaderNodeBsdfAnisotropic": "Color", "ShaderNodeBsdfGlass": "Color",
             "ShaderNodeBsdfRefraction": "Color", "ShaderNodeBsdfTranslucent": "Color",
             "ShaderNodeBsdfTransparent": "Color", "ShaderNodeBsdfSheen": "Color", "ShaderNodeBsdfToon": "Color",
             "ShaderNodeSubsurfaceScattering": "Color", "ShaderNodeBsdfMetallic": "Base Color",
             "ShaderNodeBsdfRayPortal": "Color", "ShaderNodeBsdfHair": "Color", "ShaderNodeBsdfHairPrincipled": "Color"}


def albedo_socket(node) -> str | None:
    """The input whose colour is the diffuse albedo a surface shader node renders with, or None."""
    if node.bl_idname == "ShaderNodeBsdfPrincipled":
        return "Base Color"
    if node.bl_idname == "ShaderNodeBsdfDiffuse":
        return "Color"
    return _COLOURED.get(node.bl_idname)


@dataclass(frozen=True)
class SurfaceLook:
    """Albedo and emitted radiance (W·m⁻²·sr⁻¹·nm⁻¹) over the wavelength grid."""

    reflectance: np.ndarray
    emission: np.ndarray
    holdout: bool = False  # the material holds out (its Holdout closures' weight, above 0)
    texture: ImageTexture | None = None  # the albedo's image (`reflectance` is then its socket's value)

    def emits(self) -> bool:
        return bool(np.any(self.emission > 0))


def default_look() -> SurfaceLook:
    reflectance = reflectance_spectrum((DEFAULT_ALBEDO,) * 3).values
    return SurfaceLook(reflectance, np.zeros_like(reflectance))


def _albedo(node, name, owner, notes, weight, look):
    """Add the albedo of `node`'s colour input `name`: its colour, or for an Image Texture the tracer renders, the
    socket's value, the texture being kept in `look` (`read_surface_shader` keeps it where it is the only albedo)."""
    texture = image_texture(node, name, owner, notes)
    if texture is None:
        value = colour(node, name, owner, notes)
    else:
        value = finite(tuple(float(v) for v in node.inputs[name].default_value[:3]),
                       f"{owner} ▸ {node.name} ▸ {name}")
        look["textures"].append((texture, weight))
    look["albedos"] += 1
    look["reflectance"] += weight * reflectance_spectrum(value).values


def _principled(node, owner, notes, weight, look):
    _albedo(node, "Base Color", owner, notes, weight, look)
    strength = max(float(number(node, "Emission Strength", owner, notes)), 0.0)
    if strength > 0:
        look["emission"] += weight * strength * emission_spectrum(colour(node, "Emission Color", owner, notes)).values
    layers = ["specular"] + [name for socket, name in _PRINCIPLED_LAYERS
                             if socket in node.inputs and float(number(node, socket, owner, notes)) > 0]
    if float(number(node, "Alpha", owner, notes)) < 1:
        layers.append("transparency (Alpha)")
    notes.add(f"{owner} ▸ {node.name}: rendered as its diffuse Base Color, without {', '.join(layers)}")


def _closure(node, owner, notes, weight, look):
    kind = node.bl_idname
    if kind == "ShaderNodeBsdfPrincipled":
        _principled(node, owner, notes, weight, look)
    elif kind == "ShaderNodeBsdfDiffuse":
        _albedo(node, "Color", owner, notes, weight, look)
        if float(number(node, "Roughness", owner, notes)) > 0:
            notes.add(f"{owner} ▸ {node.name}: Roughness rendered as 0 (Lambert)")
    elif kind == "ShaderNodeEmission":
        strength = max(float(number(node, "Strength", owner, notes)), 0.0)
        if strength > 0:
            look["emission"] += weight * strength * emission_spectrum(colour(node, "Color", owner, notes)).values
    elif kind == "ShaderNodeHoldout":
        look["holdout"] += weight
    elif kind == "ShaderNodeAddShader":
        for socket in node.inputs:
            _follow(socket, owner, notes, weight, look)
    elif kind == "ShaderNodeMixShader":
        fac = float(np.clip(number(node, "Fac", owner, notes), 0.0, 1.0))
        _follow(node.inputs[1], owner, notes, weight * (1.0 - fac), look)
        _follow(node.inputs[2], owner, notes, weight * fac, look)
    elif kind in _COLOURED:
        look["reflectance"] += weight * reflectance_spectrum(colour(node, albedo_socket(node), owner, notes)).values
        look["albedos"] += 1
        notes.add(f"{owner} ▸ {node.name}: {node.bl_label or kind} rendered as a diffuse surface of its colour")
    else:
        notes.add(f"{owner} ▸ {node.name}: {node.bl_label or kind} is not a surface shader the exporter converts: "
                  "rendered black")


def _follow(socket, owner, notes, weight, look):
    found = source(socket)
    if found is not None and weight > 0:
        _closure(found[0], owner, notes, weight, look)


def read_surface_shader(material, notes: Notes) -> SurfaceLook | None:
    """What the material's surface renders as; None where nothing is linked to its Surface (see-through)."""
    if material is None or material.node_tree is None:
        return default_look()
    found = output_source(material.node_tree, "Surface")
    if found is None:
        return None
    zeros = np.zeros(GRID.size)
    look = {"reflectance": zeros.copy(), "emission": zeros.copy(), "holdout": 0.0, "albedos": 0, "textures": []}
    owner = f"material {material.name!r}"
    _closure(found[0], owner, notes, 1.0, look)
    if 0.0 < look["holdout"] < 1.0:
        notes.add(f"{owner}: Holdout mixed in at weight {look['holdout']:.3g} rendered as a whole holdout")
    texture = None
    if look["textures"] and look["albedos"] == 1 and look["textures"][0][1] == 1.0:
        texture = look["textures"][0][0]
    for unused, _weight in look["textures"][1 if texture is not None else 0:]:
        notes.add(f"{owner} ▸ {unused.node.name}: an Image Texture mixed with other shaders' colours is not "
                  "rendered (its socket's value is)")
    return SurfaceLook(np.clip(look["reflectance"], 0.0, 1.0), look["emission"], look["holdout"] > 0.0, texture)
