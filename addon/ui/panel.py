"""The base of the add-on's panels, as the Cycles add-on's `CyclesButtonsPanel`: shown while Spectral
Volume is the render engine (`COMPAT_ENGINES`) and laid out as Blender's own panels, labels left of their
fields (property split) and keyframe decorators right of them. A panel draws its settings in
`draw_settings(layout, context)`; rows that hold several fields turn the split off for themselves."""

from ..props.render import ENGINE_ID


class SpectralPanel:
    COMPAT_ENGINES = {ENGINE_ID}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = True
        self.draw_settings(layout, context)

    def draw_settings(self, layout, context) -> None:
        raise NotImplementedError
