"""Render jobs (addon/jobs/): one protocol for the tracer and the Cycles emulation, chosen in one place."""

import inspect
import re
from pathlib import Path

import pytest

from addon.jobs import kinds
from addon.cycles_emulation.job import EmulationJob
from addon.export.scene import export_scene
from addon.jobs.protocol import Job
from addon.jobs.tracer_job import TracerJob
from tests.addon.builders import basic_scene

bpy = pytest.importorskip("bpy")

ADDON = Path(__file__).resolve().parents[2] / "addon"
KINDS = {"TRACER": TracerJob, "CYCLES": EmulationJob}


def _protocol() -> list[str]:
    return [name for name in dir(Job) if not name.startswith("_")]


@pytest.mark.parametrize("kind", KINDS.values())
def test_every_kind_offers_the_whole_protocol_with_its_signatures(kind):
    assert issubclass(kind, Job) and not inspect.isabstract(kind)
    for name in _protocol():
        ours, protocol = inspect.getattr_static(kind, name), inspect.getattr_static(Job, name)
        if isinstance(protocol, (property, classmethod)):
            assert type(ours) is type(protocol), name  # a property stays a property, a class method one
        if callable(getattr(Job, name)):
            ours, protocol = inspect.signature(getattr(kind, name)), inspect.signature(getattr(Job, name))
            assert list(ours.parameters) == list(protocol.parameters), name


@pytest.mark.parametrize("renderer", KINDS)
def test_the_render_settings_choose_the_kind_and_its_job(registered, tmp_path, renderer):
    scene, _cloud = basic_scene(tmp_path)
    scene.spectral.renderer = renderer
    assert kinds.kind(scene.spectral) is KINDS[renderer]
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = kinds.render_job(scene, export, spp=2)
    assert type(job) is KINDS[renderer]
    assert (job.fraction, job.message, job.result, job.error) == (0.0, None, None, None)
    assert isinstance(job.warnings, list) and job.describe() and not job.succeeded
    assert (job.engine_refusal is None) == (renderer == "TRACER")  # F12 cannot run the emulation


def test_only_jobs_reads_the_renderer_to_choose():
    """Every other module asks `jobs` (the panels only draw the chosen renderer's settings; props define it)."""
    readers = sorted(str(path.relative_to(ADDON)) for path in ADDON.rglob("*.py")
                     if path.parts[len(ADDON.parts)] not in ("ui", "props")
                     and re.search(r"\.renderer\b", path.read_text(encoding="utf-8")))
    assert readers == ["jobs/kinds.py"]
