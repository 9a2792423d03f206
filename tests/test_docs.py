"""The docs name only what exists: every module or folder path in docs/architecture.md (and the repository
paths the other docs name) is a file or folder of the repository, so a move or a rename that forgets the
docs fails here."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TRACER = ROOT / "addon" / "tracer"
TOP_FOLDERS = ("addon", "tests", "bench", "docs", "tools", "osl", "demo_blends")
# A repository path: a top folder, then names, ending in a file with an extension or in a folder's "/".
REPOSITORY_PATH = re.compile(rf"(?<![\w./-])((?:{'|'.join(TOP_FOLDERS)})/(?:[\w.-]+/)*(?:[\w-]+\.\w+|))")
# The tracer's own modules as docs/architecture.md names them in code spans: `kernels/media.py`, `layout.py`.
TRACER_MODULE = re.compile(r"`((?:kernels/)?\w+\.py)`")
LINK = re.compile(r"\]\(([\w./-]+\.md)(?:#[\w-]*)?\)")
DOCS = [ROOT / "README.md", ROOT / "bench" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def repository_paths(text: str) -> set[str]:
    return {match.group(1) for match in REPOSITORY_PATH.finditer(text)}


def missing_paths(document: Path) -> list[str]:
    text = document.read_text(encoding="utf-8")
    missing = [path for path in sorted(repository_paths(text)) if not (ROOT / path).exists()]
    missing += [link for link in sorted(set(LINK.findall(text))) if not (document.parent / link).exists()]
    return missing


def test_architecture_names_only_paths_that_exist():
    document = ROOT / "docs" / "architecture.md"
    text = document.read_text(encoding="utf-8")
    assert len(repository_paths(text)) > 40  # the reader below finds the paths it is meant to check
    assert not missing_paths(document)
    modules = set(TRACER_MODULE.findall(text))
    assert "kernels/media.py" in modules
    addon_modules = {path.name for path in (ROOT / "addon").rglob("*.py")}
    missing = [name for name in sorted(modules) if not (TRACER / name).exists()
               and not ("/" not in name and name in addon_modules)]
    assert not missing


def test_architecture_names_every_module_at_addons_root_and_every_package():
    """A module added at addon/'s root, or a package anywhere under it, has its place in the architecture."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    parts = [path.relative_to(ROOT).as_posix() for path in sorted((ROOT / "addon").glob("*.py"))]
    parts += [init.parent.relative_to(ROOT).as_posix() + "/" for init in sorted((ROOT / "addon").rglob("*/__init__.py"))]
    assert "addon/tracer/kernels/" in parts
    assert not [part for part in parts if part not in repository_paths(text)]


@pytest.mark.parametrize("document", DOCS, ids=lambda path: path.relative_to(ROOT).as_posix())
def test_docs_name_only_paths_that_exist(document):
    assert not missing_paths(document)


def test_the_path_reader_finds_paths_and_only_paths():
    text = ("see `addon/tracer/kernels/media.py`, addon/export/ and tests/tracer/test_phase.py; not "
            "my_addon/x.py, https://example.org/docs/x.md or `kernels/media.py`")
    assert repository_paths(text) == {"addon/tracer/kernels/media.py", "addon/export/", "tests/tracer/test_phase.py"}


def test_no_code_cites_a_design_note_outside_the_repository():
    """The code and the tests cite docs/architecture.md, which a clone has, not a file beside the repository."""
    citing = [path.relative_to(ROOT).as_posix() for folder in ("addon", "tests", "bench", "tools", "demo_blends")
              for path in (ROOT / folder).rglob("*.py")
              if "DESIGN.md" in path.read_text(encoding="utf-8") and path != Path(__file__).resolve()]
    assert not citing
