"""Reading Blender shader node trees as constants: what feeds a socket, through reroutes and muted nodes.

The exporter converts the parts of a node tree that have a meaning without a renderer's shader VM: a
socket's own value, a Value or RGB node, a Blackbody node of constant temperature, an Attribute node
naming a grid. Anything else feeding an input (a texture, maths on coordinates) cannot be converted:
the input is read at its default value and a `notes.Notes` entry names the data block, node and input, so
the render report can say what was not rendered as set.
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
