"""The extension zip builds, validates, installs into a throw-away Blender user folder and enables."""

import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PLATFORM = {"linux": "linux-x64", "win32": "windows-x64"}.get(sys.platform, "macos-arm64")


@pytest.fixture(scope="module")
def extension_zip(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension.py"), "--platform", PLATFORM,
                    "--out", str(out)], check=True)
    (package,) = out.glob("*.zip")
    return package


def test_zip_holds_the_addon_and_wheels_but_no_tests(extension_zip):
    import zipfile

    names = zipfile.ZipFile(extension_zip).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert "addon/tracer/__init__.py" in names
    assert any(re.match(r"wheels/numba-.*\.whl$", n) for n in names)
    assert not any(n.startswith(("tests/", "bench/", "out/", "demo_blends/", ".venv/")) for n in names)
    assert not any("__pycache__" in n for n in names)


INSTALL_SCRIPT = textwrap.dedent(
    """
    import os, sys
    import bpy
    result = bpy.ops.extensions.package_install_files(
        filepath=sys.argv[1], repo="user_default", enable_on_install=True)
    assert result == {"FINISHED"}, result
    module = "bl_ext.user_default.spectral_volume"
    assert module in bpy.context.preferences.addons.keys(), "add-on not enabled"
    assert hasattr(bpy.types.Scene, "spectral"), "scene settings not registered"
    assert hasattr(bpy.types, "SPECTRAL_PT_sidebar"), "sidebar panel not registered"
    site = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                        "python%d.%d" % sys.version_info[:2], "site-packages")
    assert {"numba", "llvmlite", "colour", "scipy", "dask", "distributed"} <= set(os.listdir(site)), os.listdir(site)
    import importlib, subprocess
    background = importlib.import_module(module + ".addon.tracer.background_compile")
    child = subprocess.run(background.child_command("describe"), env=background.child_environment(),
                           capture_output=True, text=True, timeout=120)
    assert child.stdout.startswith(module + ".addon.tracer "), child.stdout + child.stderr  # its own cache key
    bpy.ops.preferences.addon_disable(module=module)
    assert not hasattr(bpy.types.Scene, "spectral"), "scene settings left after disable"
    assert not hasattr(bpy.types, "SPECTRAL_PT_sidebar"), "panel left after disable"
    print("INSTALL-OK")
    """
)


def test_zip_installs_enables_and_disables_cleanly(extension_zip, tmp_path):
    user = tmp_path / "blender_user"
    user.mkdir()
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = {**__import__("os").environ, "BLENDER_USER_RESOURCES": str(user)}
    done = subprocess.run([sys.executable, str(script), str(extension_zip)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert "INSTALL-OK" in done.stdout, done.stdout + done.stderr


def test_bundled_wheels_match_the_pinned_environment():
    """The add-on inside Blender runs the same numba/llvmlite/scipy/colour-science the tests run."""
    pins = dict(
        line.split("==") for line in (ROOT / "requirements.lock").read_text().splitlines()
        if "==" in line and not line.startswith("#")
    )
    pins = {name.lower().replace("_", "-"): version for name, version in pins.items()}
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    for wheel in manifest["wheels"]:
        name, version, *_rest, platform_tag = Path(wheel).name[:-4].split("-")
        if "macosx" in platform_tag and "x86_64" in platform_tag:
            continue  # Intel macs: last numba/llvmlite with wheels, stated in the manifest
        assert pins[name.lower().replace("_", "-")] == version, wheel


BLENDER_SHIPS = {"numpy"}  # what the bundled wheels may rely on Blender's own Python for


def test_bundled_wheels_bring_their_whole_dependency_closure(extension_zip):
    """Blender resolves no dependencies: every requirement of a bundled wheel (on Python 3.13, this
    platform, no extras) must be another bundled wheel or something Blender ships."""
    import io
    import zipfile

    from packaging.markers import default_environment
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    environment = {**default_environment(), "python_version": "3.13", "extra": ""}
    package = zipfile.ZipFile(extension_zip)
    wheels = [n for n in package.namelist() if n.startswith("wheels/") and n.endswith(".whl")]
    bundled = {canonicalize_name(Path(w).name.split("-")[0]) for w in wheels}
    missing = set()
    for wheel in wheels:
        with zipfile.ZipFile(io.BytesIO(package.read(wheel))) as inner:
            (metadata,) = [n for n in inner.namelist() if n.endswith(".dist-info/METADATA")]
            for line in inner.read(metadata).decode().splitlines():
                if line.startswith("Requires-Dist:"):
                    requirement = Requirement(line.removeprefix("Requires-Dist:").strip())
                    if requirement.marker is None or requirement.marker.evaluate(environment):
                        missing.add(canonicalize_name(requirement.name))
    assert {"dask", "distributed"} <= bundled
    assert missing - bundled - BLENDER_SHIPS == set()


def test_tracer_imports_without_bpy():
    """`addon.tracer` must load where Blender is absent (CLI, distributed workers)."""
    code = textwrap.dedent(
        """
        import sys
        class NoBlender:
            def find_spec(self, name, path=None, target=None):
                if name == "bpy" or name.startswith("bpy."):
                    raise ImportError("bpy is blocked in this test")
        sys.meta_path.insert(0, NoBlender())
        import addon.tracer
        import pkgutil, importlib
        for info in pkgutil.walk_packages(addon.tracer.__path__, "addon.tracer."):
            if not info.name.endswith("__main__"):
                importlib.import_module(info.name)
        assert "bpy" not in sys.modules
        print("NO-BPY-OK")
        """
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert "NO-BPY-OK" in done.stdout, done.stderr
