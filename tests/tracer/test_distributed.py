"""The worker's side of a farm (addon/tracer/distributed.py): a task returns pixels only when the fingerprint of
what it runs is the one the client asked for, and the names Dask sends by reference keep their module path."""

import pickle

from addon.tracer import distributed
from addon.tracer import render as single
from tests.support.farm import small_scene


def test_a_result_is_refused_unless_its_fingerprint_is_the_tasks(monkeypatch):
    """A task whose fingerprint is not this process's returns no pixels."""
    data = distributed.SceneData(single.band_scenes(small_scene()))
    mine = distributed.fingerprint(distributed.environment(), data.digest(), 11, "numpy")
    ran = distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 11, "numpy", expected=mine)
    assert ran.fingerprint == mine and ran.sums[0].shape == (2, 2, 3)
    other = distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 12, "numpy", expected=mine)
    assert other.fingerprint != mine and other.sums is None
    monkeypatch.setattr(distributed, "sources_digest", lambda: "other sources")
    assert distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 11, "numpy", expected=mine).sums is None
    copy = pickle.loads(pickle.dumps(data))
    assert getattr(copy, "_digest", None) is None and copy.digest() == data.digest()


def test_the_names_dask_sends_by_reference_keep_this_modules_path():
    """Dask sends the task, the environment probe, the scene data and the answer by module path and name. Kept
    at `addon.tracer.distributed`, a worker started from an older checkout still finds them, runs its own code
    and answers with its own fingerprint (refused, and the task re-run elsewhere) instead of failing to import
    them, which would stop the render."""
    for name in ("render_task", "environment", "SceneData", "TaskResult"):
        value = getattr(distributed, name)
        assert (value.__module__, value.__qualname__) == ("addon.tracer.distributed", name)
        assert pickle.loads(pickle.dumps(value)) is value
