"""Spectral curves: Blender curve widgets whose x axis is the wavelength.

Each curve is a Float Curve node in a hidden node group (name starting with ".") that its owner
(a Material, Light or World) points at through `owner.spectral.curve_group`, so the group is saved,
appended and linked together with its owner. A `SpectralCurve` property names its node in that group.
Copying the owner copies the pointer, not the group: the copies share their curves until
`make_single_user` gives one its own group (the panels offer it while the group has several users).

Blender limits a curve's clipping rectangle to ±100, so x is the wavelength in hundreds of nanometres
(`NM_PER_X`): x = 5.5 is 550 nm. The panels print the selected point in nanometres.
"""

import bpy
import numpy as np

from ..tracer.wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

NM_PER_X = 100.0
GROUP_PREFIX = ".Spectral curves"


class SpectralCurve(bpy.types.PropertyGroup):
    """A reference to one Float Curve node in the owner's hidden curve group."""

    node: bpy.props.StringProperty(name="Curve Node", description="Float Curve node in the hidden curve group",
                                   options={"HIDDEN"})


CLASSES = (SpectralCurve,)


def owner_settings(curve: SpectralCurve):
    """The `spectral` settings of the ID (Material, Light, World) that owns `curve`."""
    return curve.id_data.spectral


def find_mapping(curve: SpectralCurve):
    """The curve's CurveMapping, or None when its node does not exist (yet)."""
    group = owner_settings(curve).curve_group
    if group is None or not curve.node:
        return None
    node = group.nodes.get(curve.node)
    return None if node is None else node.mapping


def find_node(curve: SpectralCurve):
    group = owner_settings(curve).curve_group
    return None if group is None or not curve.node else group.nodes.get(curve.node)


def ensure(curve: SpectralCurve, y_range=(0.0, 1.0), wavelengths=(LAMBDA_MIN, LAMBDA_MAX), values=None):
    """The curve's CurveMapping, creating the hidden group and the node when missing. A new curve runs
    through (`wavelengths`, `values`), by default flat at the middle of `y_range`."""
    mapping = find_mapping(curve)
    if mapping is not None:
        return mapping
    settings = owner_settings(curve)
    if settings.curve_group is None:
        settings.curve_group = bpy.data.node_groups.new(f"{GROUP_PREFIX} {curve.id_data.name}", "ShaderNodeTree")
    node = settings.curve_group.nodes.new("ShaderNodeFloatCurve")
    node.label = curve.path_from_id()
    curve.node = node.name
    mapping = node.mapping
    mapping.clip_min_x, mapping.clip_max_x = LAMBDA_MIN / NM_PER_X, LAMBDA_MAX / NM_PER_X
    mapping.clip_min_y, mapping.clip_max_y = y_range
    mapping.use_clip = True
    if values is None:
        values = [0.5 * (y_range[0] + y_range[1])] * len(wavelengths)
    set_points(mapping, wavelengths, values)
    return mapping


def is_shared(owner) -> bool:
    group = owner.spectral.curve_group
    return group is not None and group.users > 1


def make_single_user(owner) -> None:
    """Give `owner` its own copy of a shared curve group (node names, and so the references, stay)."""
    if is_shared(owner):
        group = owner.spectral.curve_group.copy()
        group.name = f"{GROUP_PREFIX} {owner.name}"
        owner.spectral.curve_group = group


def discard(curve: SpectralCurve) -> None:
    """Remove the curve's node (when its setting goes away)."""
    node = find_node(curve)
    if node is not None:
        node.id_data.nodes.remove(node)
    curve.node = ""


def set_points(mapping, wavelengths, values) -> None:
    """Replace the curve's points by (wavelength nm, value) pairs (at least two) and update it."""
    points = mapping.curves[0].points
    while len(points) > 2:
        points.remove(points[-1])
    coordinates = [(float(lam) / NM_PER_X, float(value)) for lam, value in zip(wavelengths, values)]
    points[0].location, points[1].location = coordinates[0], coordinates[-1]
    for x, y in coordinates[1:-1]:
        points.new(x, y)
    mapping.update()
    mapping.reset_view()


def points(mapping) -> list[tuple[float, float]]:
    """(wavelength nm, value) of the curve's points."""
    return [(p.location[0] * NM_PER_X, p.location[1]) for p in mapping.curves[0].points]


def selected_points(mapping) -> list[tuple[float, float]]:
    return [(p.location[0] * NM_PER_X, p.location[1]) for p in mapping.curves[0].points if p.select]


def sample(mapping) -> np.ndarray:
    """The curve on the wavelength grid (one value per nm, 250–830 nm)."""
    curve = mapping.curves[0]
    return np.array([mapping.evaluate(curve, lam / NM_PER_X) for lam in GRID])
