"""The extension zip builds, validates, stays small, installs into a throw-away Blender user folder, enables,
renders and denoises from there with the bundled wheels, and disables cleanly."""

import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from tests.packaging.conftest import PLATFORM

ROOT = Path(__file__).resolve().parents[2]
MB = 1e6
# Issue 31's limits for linux-x64: the zip, and all Blender writes when it installs it (the extension's
# folder, which keeps the wheels, and the packages installed from them).
ZIP_LIMIT_MB = 80
INSTALLED_LIMIT_MB = 300


def test_zip_holds_the_addon_and_wheels_but_no_tests(extension_zip):
    import zipfile

    names = zipfile.ZipFile(extension_zip).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert "addon/tracer/__init__.py" in names
    assert any(re.match(r"wheels/numba-.*\.whl$", n) for n in names)
    assert not any(n.startswith(("tests/", "bench/", "out/", "demo_blends/", ".venv/")) for n in names)
    assert not any("__pycache__" in n for n in names)
    # Mitsuba and Dr.Jit are for the benchmarks only; Blender ships Open Image Denoise (addon/tracer/denoise.py);
    # SciPy is for the tests only
    assert not any(re.match(r"wheels/(mitsuba|drjit|pyoidn|cffi|scipy)-", n) for n in names)


def test_the_wheels_in_the_zip_leave_out_what_never_runs_and_list_what_they_hold(extension_zip):
    import io
    import zipfile

    sys.path.insert(0, str(ROOT / "tools"))
    try:
        from build_extension import STRIPPED, gnu_strip, left_out
    finally:
        sys.path.remove(str(ROOT / "tools"))
    package = zipfile.ZipFile(extension_zip)
    for wheel in (n for n in package.namelist() if n.endswith(".whl")):
        inner = zipfile.ZipFile(io.BytesIO(package.read(wheel)))
        names = inner.namelist()
        distribution = Path(wheel).name.split("-")[0]
        assert not any(left_out(distribution, name) for name in names), wheel
        for library in STRIPPED.get(distribution, ()) if gnu_strip() and PLATFORM == "linux-x64" else ():
            original = zipfile.ZipFile(ROOT / "wheels" / Path(wheel).name).getinfo(library).file_size
            assert inner.getinfo(library).file_size < original - 10 * MB, library  # symbol tables gone
        (record,) = [n for n in names if n.endswith(".dist-info/RECORD")]
        listed = [line.split(",")[0] for line in inner.read(record).decode().splitlines()]
        assert sorted(listed) == sorted(names), wheel
    assert not any("htmlcov" in n for n in names)


INSTALL_SCRIPT = textwrap.dedent(
    """
    import importlib, os, subprocess, sys
    import bpy
    import numpy as np
    site = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                        "python%d.%d" % sys.version_info[:2], "site-packages")
    bundled = {"numba", "llvmlite", "colour", "dask", "distributed"}
    absent = {"scipy"}  # not bundled: nothing may need it

    class BundledOnly:  # this Python has its own copies of the bundled packages; Blender has none
        def find_spec(self, name, path=None, target=None):
            if path is None and name in bundled | absent:
                return importlib.machinery.PathFinder.find_spec(name, [site]) or self.missing(name)

        def missing(self, name):
            raise ImportError(name + " is not in the extension's packages")

    sys.meta_path.insert(0, BundledOnly())
    result = bpy.ops.extensions.package_install_files(
        filepath=sys.argv[1], repo="user_default", enable_on_install=True)
    assert result == {"FINISHED"}, result
    assert bundled <= set(os.listdir(site)) and not absent & set(os.listdir(site)), os.listdir(site)
    module = "bl_ext.user_default.spectral_volume"
    assert module in bpy.context.preferences.addons.keys(), "add-on not enabled"
    assert hasattr(bpy.types.Scene, "spectral"), "scene settings not registered"
    assert hasattr(bpy.types, "SPECTRAL_PT_sidebar"), "sidebar panel not registered"
    tracer = module + ".addon.tracer"
    for package in bundled:
        assert importlib.import_module(package).__file__.startswith(site), package
    background = importlib.import_module(tracer + ".background_compile")
    child = subprocess.run(background.child_command("describe"), env=background.child_environment(),
                           capture_output=True, text=True, timeout=120)
    assert child.stdout.startswith(tracer + " "), child.stdout + child.stderr
    # What the slimmed wheels keep runs: the RGB recoveries (the add-on's Jakob 2019, colour-science's
    # Otsu 2018), a render with the Numba kernel, and Blender's own Open Image Denoise; all without SciPy.
    b, render = importlib.import_module(tracer + ".builders"), importlib.import_module(tracer + ".render")
    spectra, denoise = importlib.import_module(tracer + ".spectra"), importlib.import_module(tracer + ".denoise")
    for method in spectra.RGB_METHODS:
        assert 0.0 < spectra.from_rgb((0.2, 0.5, 0.7), method).values.max() <= 1.0
    scene = b.scene(b.perspective((0.0, -4.0, 0.0), (0.0, 0.0, 0.0), 16, 12, 40.0),
                    [b.medium(b.box_grid(), 2.0, albedo=0.8)], [b.sun(b.direction(40.0), 3.0)], spp=4)
    film = render.render(scene, seed=1, backend="numba").film
    assert np.isfinite(film.xyz).all() and film.xyz.mean() > 0, film.xyz.mean()
    assert denoise.available(), denoise.unavailable_reason()
    assert np.isfinite(denoise.denoise(film.rgb())).all()
    assert not [name for name in sys.modules if name.split(".")[0] in absent], "SciPy imported"
    extensions = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions")
    print("INSTALLED-BYTES", sum(os.path.getsize(os.path.join(folder, name))
                                 for folder, _, names in os.walk(extensions) for name in names))
    bpy.ops.preferences.addon_disable(module=module)  # Blender removes the packages of disabled extensions
    assert not hasattr(bpy.types.Scene, "spectral"), "scene settings left after disable"
    assert not hasattr(bpy.types, "SPECTRAL_PT_sidebar"), "panel left after disable"
    print("INSTALL-OK")
    """
)


@pytest.fixture(scope="module")
def installed(extension_zip, tmp_path_factory):
    """What INSTALL_SCRIPT printed, having installed the zip into a throw-away Blender user folder."""
    user = tmp_path_factory.mktemp("blender_user")
    script = user.parent / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = {**__import__("os").environ, "BLENDER_USER_RESOURCES": str(user)}
    done = subprocess.run([sys.executable, str(script), str(extension_zip)], env=env,
                          capture_output=True, text=True, timeout=1800)  # a render that compiles takes minutes
    return done.stdout + done.stderr


def test_zip_installs_enables_renders_and_disables_cleanly(installed):
    assert "INSTALL-OK" in installed, installed


def test_the_zip_is_small(extension_zip):
    assert extension_zip.stat().st_size / MB <= ZIP_LIMIT_MB


def test_the_installed_extension_is_small(installed):
    size = int(re.search(r"^INSTALLED-BYTES (\d+)$", installed, re.MULTILINE).group(1))
    assert size / MB <= INSTALLED_LIMIT_MB, f"{size / MB:.0f} MB installed"


def test_bundled_wheels_match_the_pinned_environment():
    """The add-on inside Blender runs the same numba/llvmlite/colour-science the tests run."""
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
