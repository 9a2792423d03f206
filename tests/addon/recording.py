"""A stand-in for `bpy.types.UILayout` that records what a draw function asks for and checks it.

Background Blender has no UI to draw into, so panel tests call `draw(self, context)` with this layout:
every `prop` must name a real property (its value is read, so getters run), every operator, menu and
UI list must be registered, and operator buttons accept only their operator's properties.
"""

import inspect

import bpy

CONTAINERS = {"row", "column", "box", "split", "grid_flow", "column_flow", "panel_prop"}
SETTABLE = {"active", "enabled", "alert", "scale_x", "scale_y", "use_property_split", "use_property_decorate",
            "alignment", "operator_context", "emboss"}


def _check_property(data, name):
    assert data is not None, f"prop() on None for {name!r}"
    assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
    getattr(data, name)


class OperatorButton:
    """What `layout.operator()` returns: only the operator's own properties may be set."""

    def __init__(self, idname):
        category, name = idname.split(".")
        rna = getattr(getattr(bpy.ops, category), name).get_rna_type()
        object.__setattr__(self, "_allowed", {p.identifier for p in rna.properties})
        object.__setattr__(self, "values", {})

    def __setattr__(self, name, value):
        assert name in self._allowed, f"operator has no property {name!r}"
        self.values[name] = value

    def __getattr__(self, name):
        return self.values[name]


class RecordingLayout:
    def __init__(self, calls=None):
        object.__setattr__(self, "calls", [] if calls is None else calls)

    def __setattr__(self, name, value):
        assert name in SETTABLE, f"UILayout has no settable attribute {name!r}"
        self.calls.append(("set", (name, value), {}))

    def __getattr__(self, name):
        assert name in bpy.types.UILayout.bl_rna.functions or name in CONTAINERS, f"UILayout has no {name}()"

        def call(*args, **kwargs):
            self.calls.append((name, args, kwargs))
            return self._check(name, args, kwargs)

        return call

    def _check(self, name, args, kwargs):
        if name in CONTAINERS:
            return RecordingLayout(self.calls)
        if name in ("prop", "prop_enum", "template_curve_mapping"):
            _check_property(args[0], args[1])
        elif name == "operator":
            return OperatorButton(args[0])
        elif name == "menu":
            assert hasattr(bpy.types, args[0]), f"menu {args[0]} is not registered"
        elif name == "popover":
            panel = kwargs.get("panel", args[0] if args else None)
            assert hasattr(bpy.types, panel), f"popover panel {panel} is not registered"
        elif name == "template_list":
            assert hasattr(bpy.types, args[0]), f"UI list {args[0]} is not registered"
            _check_property(args[2], args[3])
            _check_property(args[4], args[5])
        return None

    def setting_before(self, index, name):
        """The last value `name` was set to before call `index` (None: never)."""
        values = [args[1] for kind, args, _kwargs in self.calls[:index] if kind == "set" and args[0] == name]
        return values[-1] if values else None

    def index(self, kind, data, name):
        """Index of the first `kind` call (prop, ...) on `data`'s property `name`."""
        return next(i for i, (call, args, _kwargs) in enumerate(self.calls)
                    if call == kind and args[:2] == (data, name))

    def texts(self, kind="label"):
        return [kwargs.get("text", "") for name, _args, kwargs in self.calls if name == kind]


def draw(cls, context, method="draw") -> RecordingLayout:
    """Run `cls.<method>` (a Panel, Menu or UIList class) against `context`; the recorded layout."""
    layout = RecordingLayout()

    def lookup(_self, name):  # the panel's other methods (draw_settings, ...), bound to the stand-in
        value = getattr(cls, name)
        return value.__get__(_self) if inspect.isfunction(value) else value

    getattr(cls, method)(type("Self", (), {"layout": layout, "__getattr__": lookup})(), context)
    return layout
