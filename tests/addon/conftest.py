"""Fixtures for add-on tests in Blender-as-a-module: every test starts from factory settings with the
add-on freshly registered, and unregisters it afterwards."""

import pytest

bpy = pytest.importorskip("bpy")

import addon  # noqa: E402  (after bpy: the add-on's Blender modules need it)


@pytest.fixture
def clean():
    """An empty factory-settings file, the add-on not registered."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy


@pytest.fixture
def registered(clean):
    """An empty factory-settings file with the add-on registered for this test only."""
    addon.register()
    yield bpy
    addon.unregister()
