"""The add-on's layers import one way (docs/architecture.md, "Layers: who may import whom"): the tracer
knows nothing of Blender or the add-on; settings (`props`) know nothing of what reads them (export,
panels, operators, engine). Read from the sources, so a new import that breaks a layer fails here."""

import ast
from pathlib import Path

import pytest

ADDON = Path(__file__).resolve().parents[2] / "addon"


def imported_modules(path: Path) -> set[str]:
    """The absolute names of the modules `path` imports ("addon.export.scene", "bpy"), relative imports
    resolved, at any depth in the file (imports inside functions count)."""
    package = ("addon",) + path.relative_to(ADDON).parent.parts
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else ()
            module = ".".join(base + ((node.module,) if node.module else ()))
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)  # `from . import curves`
    return names


def imports_of(package: str) -> dict[str, set[str]]:
    return {path.relative_to(ADDON).as_posix(): imported_modules(path)
            for path in sorted((ADDON / package).rglob("*.py"))}


# The one allowed exception: the VDB reader may ask Blender for its bundled `openvdb` module.
ALLOWED = {("tracer/grids.py", "bpy")}


def within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


@pytest.mark.parametrize("package, forbidden", [
    ("tracer", ("bpy", "addon.props", "addon.export", "addon.ui", "addon.operators", "addon.engine", "addon.importer")),
    ("nodes", ("addon.props", "addon.export", "addon.ui", "addon.operators", "addon.engine", "addon.importer")),
    ("props", ("addon.export", "addon.ui", "addon.operators", "addon.engine", "addon.importer")),
    ("export", ("addon.ui", "addon.operators", "addon.engine", "addon.importer")),
])
def test_layers_import_one_way(package, forbidden):
    breaches = [(path, name) for path, names in imports_of(package).items() for name in sorted(names)
                if any(within(name, layer) for layer in forbidden) and (path, name) not in ALLOWED]
    assert not breaches


def test_the_import_reader_resolves_relative_imports():
    names = imported_modules(ADDON / "props" / "spectrum.py")
    assert {"bpy", "addon.props.curves", "addon.tracer.spectra"} <= names
