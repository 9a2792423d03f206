"""Panels of the add-on: the 3D viewport sidebar tab and the Properties editor panels."""
