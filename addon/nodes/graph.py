"""Reading Blender shader node trees as constants: what feeds a socket, through reroutes and muted nodes.

The exporter converts the parts of a node tree that have a meaning without a renderer's shader VM: a
socket's own value, a Value or RGB node, a Blackbody node of constant temperature, an Attribute node
naming a grid, and, for the surfaces' albedo, an Image Texture through UVs (`image_texture`, which the
tracer renders as an image). Anything else feeding an input (another texture, maths on coordinates) cannot be
converted: the input is read at its default value and a `notes.Notes` entry names the data block, node and
input, so the render report can say what was not rendered as set.
"""

from dataclasses import dataclass

import numpy as np

from ..tracer import colorimetry, spectra
from ..tracer.errors import SpectralError
from .notes import Notes


@dataclass(frozen=True)
class Attribute:
    """An input driven by a named attribute (a volume grid)."""

    name: str


@dataclass(frozen=True)
class Blackbody:
    """A colour input fed by a Blackbody node of constant temperature (kelvin)."""

    temperature: float


def source(socket):
    """(node, output socket) feeding an input socket, through reroutes and muted nodes; None when unlinked."""
    seen = set()
    while socket.is_linked:
        link = socket.links[0]
        if not link.is_valid or link.is_muted:
            return None
        node, output = link.from_node, link.from_socket
        if node.as_pointer() in seen:
            return None
        seen.add(node.as_pointer())
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
            continue
        if node.mute:
            passing = [internal.from_socket for internal in node.internal_links if internal.to_socket == output]
            if not passing:
                return None
            socket = passing[0]
            continue
        return node, output
    return None


def output_source(tree, socket_name: str):
    """(node, output socket) feeding input `socket_name` ("Surface", "Volume") of the tree's active output
    node for Cycles, or None."""
    output = None if tree is None else (tree.get_output_node("CYCLES") or tree.get_output_node("ALL"))
    if output is None or socket_name not in output.inputs:
        return None
    return source(output.inputs[socket_name])


def _where(owner: str, node, name: str) -> str:
    return f"{owner} ▸ {node.name} ▸ {name}"


def finite(value, where: str):
    """`value` (a number or a colour) where every component is finite, else a SpectralError naming `where`:
    a script or driver can set NaN or infinity where Blender's interface cannot."""
    components = np.atleast_1d(np.asarray(value, dtype=np.float64))
    if not np.all(np.isfinite(components)):
        raise SpectralError(f"{where}: must be finite, found {', '.join(f'{c:g}' for c in components)}")
    return value


def number(node, name: str, owner: str, notes: Notes, *, attribute: bool = False):
    """The value of `node`'s input `name`: a float, or with `attribute` an `Attribute` where an Attribute
    node (Fac) feeds it. Another feeding node is noted and its default returned."""
    socket = node.inputs[name]
    found = source(socket)
    default = finite(float(socket.default_value), _where(owner, node, name))
    if found is None:
        return default
    feeder, output = found
    if feeder.bl_idname == "ShaderNodeValue":
        return finite(float(feeder.outputs[0].default_value), _where(owner, feeder, "Value"))
    if attribute and feeder.bl_idname == "ShaderNodeAttribute" and feeder.attribute_type == "GEOMETRY":
        return Attribute(feeder.attribute_name)
    notes.add(f"{_where(owner, node, name)} is driven by {feeder.name!r}, which cannot be converted: "
              f"rendered at its value {default:g}")
    return default


def colour(node, name: str, owner: str, notes: Notes):
    """The linear RGB of `node`'s colour input `name` (a tuple), or a `Blackbody` where a Blackbody node
    of constant temperature feeds it. Another feeding node is noted and the socket's value returned."""
    socket = node.inputs[name]
    found = source(socket)
    default = finite(tuple(float(value) for value in socket.default_value[:3]), _where(owner, node, name))
    if found is None:
        return default
    feeder, _output = found
    if feeder.bl_idname == "ShaderNodeRGB":
        return finite(tuple(float(value) for value in feeder.outputs[0].default_value[:3]),
                      _where(owner, feeder, "Color"))
    if feeder.bl_idname == "ShaderNodeBlackbody":
        temperature = number(feeder, "Temperature", owner, notes)
        return Blackbody(temperature)
    notes.add(f"{_where(owner, node, name)} is driven by {feeder.name!r}, which cannot be converted: "
              f"rendered at its colour ({', '.join(f'{value:.3g}' for value in default)})")
    return default


def emission_spectrum(value) -> spectra.Spectrum:
    """A colour value of `colour` as emitted light: an RGB's emission spectrum (`spectra.emission_from_rgb`),
    a Blackbody's Planck shape of luminance 1 (the Blackbody node's colour is normalised so)."""
    if isinstance(value, Blackbody):
        return spectra.blackbody_of_luminance_one(max(value.temperature, 1.0))
    return spectra.emission_from_rgb(np.maximum(value, 0.0))


def reflectance_spectrum(value) -> spectra.Spectrum:
    """A colour value of `colour` as a factor (an albedo, a tint, a coefficient): the smooth spectrum of its
    RGB (`spectra.scaled_from_rgb`; a Blackbody by the RGB of its colour)."""
    if isinstance(value, Blackbody):
        value = colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(emission_spectrum(value).values))
    return spectra.scaled_from_rgb(np.maximum(value, 0.0))


@dataclass(frozen=True)
class ImageTexture:
    """A colour input read from an Image Texture node through UVs (`image_texture`): the node and its image, the UV
    map ("": the mesh's active render map), the affine map (2, 3) of a Mapping node between them ((u', v') = A (u,
    v, 1); identity without one), and the extension and interpolation the tracer reads it with."""

    node: object
    image: object
    uv_map: str
    uv_transform: np.ndarray
    extension: str
    interpolation: str


def _uv_source(texture, owner: str, notes: Notes):
    """(UV map name, affine map (2, 3)) feeding an Image Texture's Vector, or None (noted) where something else
    feeds it: unlinked or a Texture Coordinate node's UV (the active render UV map, ""), a UV Map node, optionally
    through a Mapping node of constant inputs (Point, Texture or Vector: affine in the UV, so the corners' UVs are
    mapped as Cycles maps each point's)."""
    vector = next(socket for socket in texture.inputs if socket.identifier == "Vector")
    transform = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    found = source(vector)
    if found is not None and found[0].bl_idname == "ShaderNodeMapping":
        mapping = found[0]
        driven = any(mapping.inputs[name].is_linked for name in ("Location", "Rotation", "Scale")
                     if name in mapping.inputs)
        if driven or mapping.vector_type == "NORMAL":
            notes.add(f"{owner} ▸ {mapping.name}: a Mapping node of driven inputs or of type Normal cannot be "
                      f"converted: {texture.name} rendered as its node's colour")
            return None
        transform = _mapping_matrix(mapping)
        found = source(mapping.inputs["Vector"])
    if found is None:
        return "", transform
    if found[0].bl_idname == "ShaderNodeUVMap" and not found[0].from_instancer:
        return found[0].uv_map, transform
    if found[0].bl_idname == "ShaderNodeTexCoord" and found[1].name == "UV" and not found[0].from_instancer:
        return "", transform
    notes.add(f"{owner} ▸ {texture.name} ▸ Vector is driven by {found[0].name!r}, which the tracer does not map "
              "textures with (only UVs): the texture is not rendered")
    return None


def _mapping_matrix(mapping) -> np.ndarray:
    """The affine map (2, 3) a Mapping node of constant inputs applies to a UV point (u, v, 0), as Cycles: Point
    R (S v) + L, Texture S⁻¹ R⁻¹ (v − L), Vector R (S v) (R: the XYZ Euler rotation)."""
    from mathutils import Euler  # Blender's own Euler convention

    rotation = np.array(Euler(mapping.inputs["Rotation"].default_value).to_matrix(), dtype=np.float64)
    location = np.array(mapping.inputs["Location"].default_value, dtype=np.float64)
    scale = np.array(mapping.inputs["Scale"].default_value, dtype=np.float64)
    if mapping.vector_type == "TEXTURE":
        linear = np.diag(1.0 / np.where(scale != 0.0, scale, np.inf)) @ rotation.T
        shift = -linear @ location
    else:
        linear, shift = rotation @ np.diag(scale), (location if mapping.vector_type == "POINT" else np.zeros(3))
    return np.column_stack([linear[:2, :2], shift[:2]])


def image_texture(node, name: str, owner: str, notes: Notes) -> ImageTexture | None:
    """The Image Texture node feeding `node`'s colour input `name` through its Color output, where the tracer
    renders it (a flat projection of a single image through UVs, `_uv_source`); None where none feeds it, or
    (noted) where one does that the tracer cannot render: the caller then reads the input as `colour` does."""
    found = source(node.inputs[name])
    if found is None or found[0].bl_idname != "ShaderNodeTexImage":
        return None
    texture, output = found
    where = f"{owner} ▸ {texture.name}"
    problem = None
    if output.name != "Color":
        problem = f"its {output.name} output"
    elif texture.image is None:
        problem = "no image"
    elif texture.image.source not in ("FILE", "GENERATED"):
        problem = f"a {texture.image.source.lower()} image"
    elif texture.projection != "FLAT":
        problem = f"{texture.projection.title()} projection"
    if problem is not None:
        notes.add(f"{where}: {problem} is not a texture the tracer renders")
        return None
    uv = _uv_source(texture, owner, notes)
    if uv is None:
        return None
    extension = texture.extension if texture.extension in ("REPEAT", "EXTEND", "CLIP") else "REPEAT"
    if extension != texture.extension:
        notes.add(f"{where}: extension {texture.extension.title()} rendered as Repeat")
    interpolation = "Closest" if texture.interpolation == "Closest" else "Linear"
    if interpolation != texture.interpolation:
        notes.add(f"{where}: {texture.interpolation} interpolation rendered as Linear")
    return ImageTexture(texture, texture.image, uv[0], uv[1], extension, interpolation)
