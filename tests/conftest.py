"""Shared test settings: Blender must never touch the developer's own preferences."""

import os
import tempfile

# Set before anything imports bpy: Blender reads it once, at start-up.
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="spectral_blender_user_"))
