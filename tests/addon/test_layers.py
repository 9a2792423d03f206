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


def module_graph() -> dict[str, set[str]]:
    """Every module of the add-on → the add-on's modules it imports (a package's import is its `__init__`; a
    module's import of its own parent packages is left out: Python has run them before the module)."""
    modules = {}
    for path in ADDON.rglob("*.py"):
        parts = ("addon",) + path.relative_to(ADDON).with_suffix("").parts
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    graph = {}
    for name, path in modules.items():
        targets = set()
        for imported in imported_modules(path):
            while imported and imported not in modules:  # `from .x import name` names a module's member
                imported = imported.rpartition(".")[0]
            if imported and imported != name and not name.startswith(imported + "."):
                targets.add(imported)
        graph[name] = targets
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm, iteratively)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, targets = work[-1]
            target = next(targets, None)
            if target is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    group = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        group.append(member)
                        if member == node:
                            break
                    if len(group) > 1:
                        found.append(sorted(group))
            elif target not in index:
                index[target] = low[target] = len(index)
                stack.append(target)
                on_stack.add(target)
                work.append((target, iter(sorted(graph[target]))))
            elif target in on_stack:
                low[node] = min(low[node], index[target])
    return sorted(found)


def test_the_circle_finder_finds_a_loop_of_three():
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_circles():
    """Issue 33 untied the last ones (render ↔ background_compile: the backends' `prepare`, backends.py)."""
    assert circles(module_graph()) == []
