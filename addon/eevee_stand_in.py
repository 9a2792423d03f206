"""A Material Preview that resembles the spectral render: each spectral material keeps an EEVEE-only
Principled Volume in step with its spectral settings, so the viewport's Material Preview (EEVEE) shows the
volume's colour, density and anisotropy before any spectral render.

The two nodes (`PRINCIPLED`, and `OUTPUT`, a Material Output whose target is EEVEE) are added to the
material's node tree beside whatever the user has there: Cycles and the Cycles emulation never read an
EEVEE-only output, and nothing else in the tree changes. The values are the spectra seen by eye under D65:
- Color: the albedo's swatch (`props.swatch`: its colour under D65);
- Density: Density Scale × the extinction averaged with the weight D65 × ȳ (what the eye sees dimmed);
- Anisotropy: g at 550 nm.
Fluorescence and blackbody glow are not shown (EEVEE has no spectral light to excite or to colour them).

`sync` writes a value only when it differs, so the depsgraph handler (`sync_updated`) that calls it after
every change while this engine renders settles after one round.
"""

import bpy
import numpy as np

from .props.spectrum_values import to_spectrum
from .props.swatch import preview_colour
from .props.render import ENGINE_ID
from .tracer import colorimetry, spectra
from .tracer.errors import SpectralError
from .tracer.wavelengths import GRID

PRINCIPLED = "Spectral Volume Preview"
OUTPUT = "Spectral Volume Preview Output"
ANISOTROPY_AT_NM = 550.0


def _eye_weights() -> np.ndarray:
    """D65 × ȳ on the grid, summing to 1: the weights of an average as the eye sees it."""
    weights = spectra.illuminant("D65").values * colorimetry.xyz_weights("cie1931")[1]
    return weights / weights.sum()


def preview_values(settings) -> dict:
    """The Principled Volume inputs that stand for a material's spectral settings (`settings`:
    `material.spectral`). A spectrum in error counts as 0 (its panel shows the message)."""
    try:
        extinction = float(np.dot(to_spectrum(settings.extinction).values, _eye_weights()))
    except SpectralError:
        extinction = 0.0
    try:
        anisotropy = float(np.interp(ANISOTROPY_AT_NM, GRID, to_spectrum(settings.anisotropy).values))
    except SpectralError:
        anisotropy = 0.0
    return {"Color": (*preview_colour(settings.albedo), 1.0), "Density": settings.density_scale * extinction,
            "Anisotropy": anisotropy}


def _nodes(material):
    """The material's preview nodes, made (and linked) when missing."""
    tree = material.node_tree
    principled = tree.nodes.get(PRINCIPLED)
    if principled is None:
        principled = tree.nodes.new("ShaderNodeVolumePrincipled")
        principled.name = principled.label = PRINCIPLED
        principled.location = (-300.0, -400.0)
    output = tree.nodes.get(OUTPUT)
    if output is None:
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        output.name = output.label = OUTPUT
        output.target = "EEVEE"
        output.location = (0.0, -400.0)
    if not output.inputs["Volume"].is_linked:
        tree.links.new(principled.outputs["Volume"], output.inputs["Volume"])
    return principled, output


def _differs(current, wanted) -> bool:
    return not np.allclose(np.atleast_1d(np.asarray(current, dtype=np.float64)), np.atleast_1d(wanted), rtol=1e-6,
                           atol=1e-9)


def sync(material) -> bool:
    """Bring the material's preview nodes in step with its spectral settings; True when anything changed.
    Materials that are not spectral are left alone."""
    if not material.spectral.enabled:
        return False
    if material.node_tree is None:  # a material of an older file without nodes
        return False
    changed = material.node_tree.nodes.get(PRINCIPLED) is None or material.node_tree.nodes.get(OUTPUT) is None
    principled, output = _nodes(material)
    if not output.is_active_output:
        output.is_active_output = True
        changed = True
    for name, value in preview_values(material.spectral).items():
        socket = principled.inputs[name]
        if _differs(socket.default_value, value):
            socket.default_value = value
            changed = True
    return changed


_engines_seen: dict = {}  # scene name → the render engine `sync_updated` last saw it use


@bpy.app.handlers.persistent
def sync_updated(scene, depsgraph) -> None:
    """After a change, while this engine renders the scene: sync the materials that changed, or all of
    them when the scene has just switched to this engine (not on every other scene update: moving an
    object updates the scene too, and a large file has many materials)."""
    switched = _engines_seen.get(scene.name) != scene.render.engine
    _engines_seen[scene.name] = scene.render.engine
    if scene.render.engine != ENGINE_ID:
        return
    changed = {update.id.original for update in depsgraph.updates if isinstance(update.id, bpy.types.Material)}
    for material in bpy.data.materials if switched else changed:
        if material.library is None:
            sync(material)


@bpy.app.handlers.persistent
def sync_all(_=None) -> None:
    """After a file loads: sync every spectral material of a scene this engine renders."""
    if any(scene.render.engine == ENGINE_ID for scene in bpy.data.scenes):
        for material in bpy.data.materials:
            if material.library is None:
                sync(material)


CLASSES = ()
HANDLERS = ((bpy.app.handlers.depsgraph_update_post, sync_updated), (bpy.app.handlers.load_post, sync_all))

