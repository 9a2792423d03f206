"""What fills the installed extension (issue 31 item 3): builds the linux-x64 zip (or takes `--zip`), installs and enables it
into a throw-away Blender user folder with the `bpy` module and prints, in MB, the zip, everything Blender wrote,
each bundled distribution's installed files, the wheels Blender keeps beside them, the add-on's own files,
and the largest sub-folders and files."""

import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MB = 1e6

INSTALL = textwrap.dedent(
    """
    import sys
    import bpy
    result = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default",
                                                      enable_on_install=True)
    assert result == {"FINISHED"}, result
    """
)


def sizes(folder: Path) -> dict[Path, int]:
    return {Path(top, name): os.path.getsize(Path(top, name)) for top, _, names in os.walk(folder) for name in names}


def distribution(entry: str) -> str:
    """The distribution a top-level site-packages entry belongs to (`scipy.libs`, `numba-0.68.1.dist-info`…)."""
    name = re.split(r"[-.]", entry)[0]
    return {"colour_science": "colour", "pyyaml": "yaml", "_yaml": "yaml", "tlz": "toolz"}.get(name, name).lower()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--zip", type=Path, help="an extension zip (default: build linux-x64 now)")
    parser.add_argument("--top", type=int, default=12, help="how many of the largest folders and files to list")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="install_size_") as tmp:
        package = args.zip
        if package is None:
            subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension.py"), "--platform", "linux-x64",
                            "--out", tmp], check=True)
            (package,) = Path(tmp).glob("*.zip")
        user = Path(tmp) / "user"
        (Path(tmp) / "install.py").write_text(INSTALL)
        subprocess.run([sys.executable, str(Path(tmp) / "install.py"), str(package)], check=True,
                       env={**os.environ, "BLENDER_USER_RESOURCES": str(user)}, capture_output=True)
        files = sizes(user / "extensions")
        site = next((user / "extensions" / ".local" / "lib").glob("python*/site-packages"))
        extension = user / "extensions" / "user_default" / "spectral_volume"
        by_distribution, wheels, folders = collections.Counter(), collections.Counter(), collections.Counter()
        for path, size in files.items():
            if path.is_relative_to(site):
                parts = path.relative_to(site).parts
                by_distribution[distribution(parts[0])] += size
                folders["/".join(parts[:2]) if len(parts) > 2 else parts[0]] += size
            elif path.is_relative_to(extension / "wheels"):
                wheels[distribution(path.name.split("-")[0])] += size
                wheels["(all wheels)"] += size
            else:
                by_distribution["(the add-on's own files)"] += size
        print(f"zip: {package.stat().st_size / MB:.1f} MB")
        print(f"installed: {sum(files.values()) / MB:.1f} MB")
        print("\ninstalled, per distribution (MB): files | its wheel kept by Blender")
        for name, size in by_distribution.most_common():
            print(f"  {name:28s} {size / MB:7.1f} | {wheels.get(name, 0) / MB:5.1f}")
        print(f"  {'(all wheels)':28s} {'':7s} | {wheels['(all wheels)'] / MB:5.1f}")
        print("\nlargest sub-folders of site-packages (MB):")
        for name, size in folders.most_common(args.top):
            print(f"  {name:40s} {size / MB:7.1f}")
        print("\nlargest files (MB):")
        for path, size in sorted(files.items(), key=lambda item: -item[1])[: args.top]:
            print(f"  {path.relative_to(user / 'extensions').as_posix():70s} {size / MB:7.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
