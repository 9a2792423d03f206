"""Build the Blender extension zip(s) with Blender's own builder and validate them.

The wheels listed in blender_manifest.toml are downloaded (exact files, no dependency
resolution) into wheels/ when missing. The build runs from a staging copy of the files named in
the manifest's [build] paths, so a build for a subset of platforms (`--platform linux-x64`, used
by the tests) carries only that platform's wheels. One zip per platform is written to --out.

The zip carries slimmed copies of the wheels (`slim_wheel`, kept in wheels/slim-<rules digest>/): the
files in LEFT_OUT, which never run in Blender, are left out, the libraries in STRIPPED lose their symbol
tables, the rest is compressed with LZMA instead of Deflate, and RECORD lists what is left. Blender keeps
the wheels beside the files it installs from them, so both count in the installed size.

The zip for the platform the build runs on also carries a portable kernel (`add_prebuilt_kernel`), so
that the first render after installing it need not compile.
"""

import argparse
import base64
import csv
import fnmatch
import functools
import hashlib
import importlib.util
import io
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = ROOT / "blender_manifest.toml"

# Blender platform name -> substrings that identify its wheels' platform tags.
PLATFORM_TAGS = {
    "linux-x64": ("linux", "x86_64"),
    "windows-x64": ("win_amd64",),
    "macos-arm64": ("macosx", "arm64"),
    "macos-x64": ("macosx", "x86_64"),
}


# Files of the bundled wheels that never run in Blender (patterns on paths inside a wheel; "*": every
# wheel): test suites; colour-science's coverage report (78 MB) and examples.
LEFT_OUT = {
    "*": ("*/tests/*", "*/test/*"),
    "colour_science": ("colour/htmlcov/*", "colour/examples/*"),
}


# Shared libraries of the bundled wheels whose symbol tables (names for debuggers and linkers, never read
# at run time; the dynamic symbols that load them stay) are stripped with GNU strip where it is at hand
# (Linux builds): libllvmlite.so's are 19 MB of its 179 MB.
STRIPPED = {"llvmlite": ("llvmlite/binding/libllvmlite.so",)}


def left_out(distribution: str, path: str) -> bool:
    """Whether `path`, inside a wheel of `distribution` (its file name's first part), stays out of the zip."""
    patterns = LEFT_OUT["*"] + LEFT_OUT.get(distribution, ())
    return any(fnmatch.fnmatchcase(path, pattern) for pattern in patterns)


def slim_wheel(source: Path, folder: Path) -> Path:
    """The copy of wheel `source` in `folder` without the files in LEFT_OUT, LZMA-compressed (made once)."""
    target = folder / source.name
    if target.is_file():
        return target
    folder.mkdir(parents=True, exist_ok=True)
    distribution = source.name.split("-")[0]
    partial = target.with_suffix(".partial")
    with zipfile.ZipFile(source) as wheel, zipfile.ZipFile(partial, "w", zipfile.ZIP_LZMA) as slim:
        (record,) = [n for n in wheel.namelist() if n.endswith(".dist-info/RECORD")]
        rows = io.StringIO()
        listing = csv.writer(rows, lineterminator="\n")
        for info in wheel.infolist():
            if info.filename == record or left_out(distribution, info.filename):
                continue
            data = wheel.read(info)
            if info.filename in STRIPPED.get(distribution, ()):
                data = stripped(data)
            slim.writestr(info, data, zipfile.ZIP_LZMA)
            digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            listing.writerow((info.filename, f"sha256={digest}", len(data)))
        listing.writerow((record, "", ""))
        slim.writestr(wheel.getinfo(record), rows.getvalue(), zipfile.ZIP_LZMA)
    partial.replace(target)
    return target


@functools.cache
def gnu_strip() -> str | None:
    """GNU strip (binutils), which strips ELF libraries on any machine it runs on; None without it."""
    strip = shutil.which("strip")
    version = subprocess.run([strip, "--version"], capture_output=True, text=True).stdout if strip else ""
    return strip if "GNU" in version else None


def stripped(data: bytes) -> bytes:
    """An ELF shared library without its symbol tables (`strip --strip-unneeded`); as it is without GNU strip,
    or when it is not ELF (Windows, macOS)."""
    if gnu_strip() is None or not data.startswith(b"\x7fELF"):
        return data
    with tempfile.TemporaryDirectory(prefix="spectral_strip_") as tmp:
        library = Path(tmp) / "library.so"
        library.write_bytes(data)
        subprocess.run([gnu_strip(), "--strip-unneeded", str(library)], check=True)
        return library.read_bytes()


def slim_folder() -> Path:
    """Where the slimmed wheels are kept: one folder per version of LEFT_OUT and STRIPPED (and whether
    this machine strips)."""
    rules = json.dumps([LEFT_OUT, STRIPPED, gnu_strip() is not None], sort_keys=True)
    rules = hashlib.sha256(rules.encode()).hexdigest()[:12]
    return ROOT / "wheels" / f"slim-{rules}"


def blender_ext_script() -> Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("error: the bpy module is not installed; run `make setup` first")
    found = sorted(Path(spec.submodule_search_locations[0]).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        sys.exit("error: Blender's extension builder (bl_pkg/cli/blender_ext.py) is missing from the bpy wheel")
    return found[-1]


def wheel_platforms(filename: str) -> tuple[str, ...]:
    """The Blender platforms a wheel is for: () for a pure-Python wheel, both macOS ones for universal2."""
    platform_tag = filename[: -len(".whl")].split("-")[-1]
    if platform_tag == "any":
        return ()
    if "macosx" in platform_tag and "universal2" in platform_tag:
        return ("macos-arm64", "macos-x64")
    for platform, markers in PLATFORM_TAGS.items():
        if all(marker in platform_tag for marker in markers):
            return (platform,)
    raise SystemExit(f"error: cannot tell which platform wheel {filename!r} is for")


def serves(filename: str, platforms: list[str]) -> bool:
    """Whether a wheel belongs in a build for `platforms` (pure-Python wheels belong in every build)."""
    targets = wheel_platforms(filename)
    return not targets or not set(targets).isdisjoint(platforms)


def download_wheel(filename: str, dest: Path) -> None:
    """Download exactly `filename` from the package index into `dest`."""
    name, version, python_tag, _abi, platform_tag = filename[: -len(".whl")].split("-")
    command = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:",
               "--dest", str(dest), f"{name}=={version}"]
    if platform_tag != "any":
        if python_tag.startswith("cp"):  # built for one CPython (cp313 → 3.13); py3 wheels: this interpreter's
            digits = python_tag.removeprefix("cp")
            command += ["--python-version", digits[0] + "." + digits[1:]]
        for tag in platform_tag.split("."):
            command += ["--platform", tag]
    print(f"downloading {filename}", flush=True)
    subprocess.run(command, check=True)
    if not (dest / filename).is_file():
        got = ", ".join(p.name for p in dest.glob(f"{name}-*.whl")) or "nothing"
        raise SystemExit(f"error: expected {filename} from the index, got {got}")


def staged_manifest(text: str, platforms: list[str], wheels: list[str]) -> str:
    """The manifest text restricted to `platforms` and their `wheels`.

    The [build] section is dropped: the staging folder already holds only the listed paths, and
    Blender 5.2's builder miscounts wheels under --split-platforms when [build] paths is set.
    """
    text = re.sub(r"(?ms)^\[build\].*?(?=^\[|\Z)", "", text)
    text = re.sub(r"(?m)^platforms = \[.*\]$", "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]", text)
    wheel_block = "wheels = [\n" + "".join(f'  "{w}",\n' for w in wheels) + "]"
    return re.sub(r"(?ms)^wheels = \[.*?^\]", lambda _m: wheel_block, text)


def build(platforms: list[str], out_dir: Path) -> list[Path]:
    manifest_text = MANIFEST.read_text()
    manifest = tomllib.loads(manifest_text)
    unknown = set(platforms) - set(manifest["platforms"])
    if unknown:
        raise SystemExit(f"error: platform(s) {sorted(unknown)} not in the manifest's {manifest['platforms']}")
    wheels = [w for w in manifest["wheels"] if serves(Path(w).name, platforms)]

    wheel_dir = ROOT / "wheels"
    wheel_dir.mkdir(exist_ok=True)
    for wheel in wheels:
        if not (ROOT / wheel).is_file():
            download_wheel(Path(wheel).name, wheel_dir)

    out_dir.mkdir(parents=True, exist_ok=True)
    script = blender_ext_script()
    with tempfile.TemporaryDirectory(prefix="spectral_ext_") as tmp:
        stage = Path(tmp)
        for entry in manifest["build"]["paths"]:
            source = ROOT / entry
            if source.is_dir():
                shutil.copytree(source, stage / entry, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
            else:
                shutil.copy2(source, stage / entry)
        (stage / "wheels").mkdir()
        for wheel in wheels:
            shutil.copy2(slim_wheel(ROOT / wheel, slim_folder()), stage / "wheels")
        (stage / "blender_manifest.toml").write_text(staged_manifest(manifest_text, platforms, wheels))
        run([sys.executable, str(script), "build", "--source-dir", str(stage),
             "--output-dir", str(out_dir), "--split-platforms"])
    built = [out_dir / f"{manifest['id']}-{manifest['version']}-{p.replace('-', '_')}.zip" for p in platforms]
    for package, name in zip(built, platforms):
        if name == host_platform():
            add_prebuilt_kernel(package)
        run([sys.executable, str(script), "validate", str(package)])
    return built


def host_platform() -> str:
    """The Blender platform name of the computer the build runs on."""
    if sys.platform == "darwin":
        return "macos-arm64" if platform.machine() == "arm64" else "macos-x64"
    return {"linux": "linux-x64", "win32": "windows-x64"}.get(sys.platform, sys.platform)


# Compiles the kernel for Numba's generic CPU (see add_prebuilt_kernel) and prints its folder.
PORTABLE_COMPILE = """
from addon.tracer import precompile
from addon.tracer.kernels import numba_cache
precompile.compile_kernel()
print(numba_cache.kernel_folder())
"""


def add_prebuilt_kernel(package: Path) -> None:
    """Add to `package` the Numba kernel compiled for the generic CPU of this platform, with this Python's
    Numba (the version the zip bundles), from the sources the zip holds, in the folder of its key under
    addon/tracer/kernels/prebuilt/ (addon/tracer/kernels/numba_cache.py). It is compiled in a child process
    into the per-user kernel cache, where later builds of the same sources find it."""
    env = {**os.environ, "NUMBA_CPU_NAME": "generic", "PYTHONPATH": str(ROOT),
           "SPECTRAL_VOLUME_NO_PREBUILT": "1"}
    env.pop("NUMBA_CPU_FEATURES", None)
    done = subprocess.run([sys.executable, "-c", PORTABLE_COMPILE], cwd=ROOT, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"error: compiling the portable kernel failed:\n{done.stderr}")
    folder = Path(done.stdout.strip().splitlines()[-1])
    files = [folder / "key.json", *sorted(folder.glob("*.nb[ic]"))]
    with zipfile.ZipFile(package, "a", compression=zipfile.ZIP_DEFLATED) as archive:
        for file in files:
            archive.write(file, f"addon/tracer/kernels/prebuilt/{folder.name}/{file.name}")


def run(command: list) -> None:
    """Run a build step; a failure ends the build with the step's own message above it."""
    if subprocess.run(command).returncode != 0:
        raise SystemExit(f"error: {Path(command[1]).name} {command[2]} failed (see its messages above)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=ROOT / "dist", help="output folder for the zips")
    parser.add_argument("--platform", action="append", choices=sorted(PLATFORM_TAGS),
                        help="build only for this platform (repeatable); default: every platform")
    args = parser.parse_args(argv)
    platforms = args.platform or tomllib.loads(MANIFEST.read_text())["platforms"]
    for package in build(platforms, args.out.resolve()):
        print(f"built and validated {package}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
