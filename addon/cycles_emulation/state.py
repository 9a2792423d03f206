"""Temporary changes to the user's scene, undone in reverse order, and temporary datablocks, removed.

Every change the emulation makes for one Cycles render goes through `Borrowed.set` (render settings,
material slots, light colours, the World, fluid domains' render visibility); `restore()` puts back the
old values and deletes what `keep` collected (materials, a World, a Text, stand-in objects and volumes),
so a finished, cancelled or failed render leaves the scene as it was. A setting that another one limits
(an image format's colour depths) is recorded before the other changes, with its own value
(`set(owner, name, getattr(owner, name))`), so it gets that value back after the other."""

import bpy


class Borrowed:
    def __init__(self):
        self._changes = []
        self._temporaries = []

    def set(self, owner, attribute: str, value) -> None:
        old = getattr(owner, attribute)
        self._changes.append((owner, attribute, old.copy() if hasattr(old, "copy") and not isinstance(
            old, bpy.types.ID) else old))
        setattr(owner, attribute, value)

    def keep(self, datablock):
        """Remember a datablock made for this render, to delete it on restore; returns it."""
        self._temporaries.append(datablock)
        return datablock

    def restore(self) -> None:
        while self._changes:
            owner, attribute, old = self._changes.pop()
            setattr(owner, attribute, old)
        while self._temporaries:
            datablock = self._temporaries.pop()
            collection = {bpy.types.Material: bpy.data.materials, bpy.types.World: bpy.data.worlds,
                          bpy.types.Text: bpy.data.texts, bpy.types.Object: bpy.data.objects,
                          bpy.types.Volume: bpy.data.volumes}[type(datablock)]
            collection.remove(datablock)

    def __enter__(self):
        return self

    def __exit__(self, *_exc):
        self.restore()
        return False
