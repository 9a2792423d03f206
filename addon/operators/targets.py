"""Which settings an operator acts on, stored in the operator's own properties.

A button passes its settings as (ID collection, ID name, path inside the ID), which survives the
file browser and redo, unlike a context pointer. `TargetProperties` is the mixin that declares them.
"""

import bpy

# bpy.data collection of each ID type that owns spectral settings.
COLLECTIONS = {"MATERIAL": "materials", "LIGHT": "lights", "WORLD": "worlds", "SCENE": "scenes", "OBJECT": "objects"}


class TargetProperties:
    id_type: bpy.props.StringProperty(options={"HIDDEN", "SKIP_SAVE"})
    id_name: bpy.props.StringProperty(options={"HIDDEN", "SKIP_SAVE"})
    data_path: bpy.props.StringProperty(options={"HIDDEN", "SKIP_SAVE"})


def point_at(properties, settings) -> None:
    """Make an operator button (its OperatorProperties) act on `settings`."""
    owner = settings.id_data
    properties.id_type = owner.id_type
    properties.id_name = owner.name
    properties.data_path = settings.path_from_id()


def resolve(operator):
    """The settings an operator was pointed at, or None when they no longer exist."""
    collection = COLLECTIONS.get(operator.id_type)
    owner = getattr(bpy.data, collection).get(operator.id_name) if collection else None
    if owner is None:
        return None
    try:
        return owner.path_resolve(operator.data_path)
    except ValueError:
        return None
