"""Property-based fuzzing (issue 30, item 7) with hypothesis, deterministic (`derandomize`) and bounded (few
examples, each cheap): the scene file reader, the CSV and spectrum readers, the VDB reader and the command
line's option combinations. Each example ends in a clear SpectralError (or exit 1 with a message) or a finite
result: never merely "it did not crash". The Blender exporter is fuzzed in tests/addon/test_export_fuzz.py."""

import copy
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from addon.tracer import cli, grids, image_io, lowering, spectra
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from addon.tracer.render import RenderResult, render_stats
from addon.tracer.scene_io import load_scene
from tests.tracer.conftest import tiny_scene_dict
from tests.tracer.test_scene_io import leaf_paths, set_path

FUZZ = settings(derandomize=True, deadline=None, database=None, max_examples=200,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

NUMBERS = st.one_of(st.integers(min_value=-(2**70), max_value=2**70), st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([0, 1, -1, 0.5, 1e-300, 1e300, 1e308, 2**63, 2**64, 10**400]))
JSON = st.recursive(st.one_of(st.none(), st.booleans(), NUMBERS, st.text(max_size=8)),
                    lambda inner: st.one_of(st.lists(inner, max_size=4),
                                            st.dictionaries(st.text(max_size=6), inner, max_size=4)),
                    max_leaves=12)
SPECTRUM_SPECS = st.one_of(
    NUMBERS,
    st.fixed_dictionaries({"type": st.just("table"), "wavelengths": st.lists(NUMBERS, max_size=5),
                           "values": st.lists(NUMBERS, max_size=5)}),
    st.fixed_dictionaries({"type": st.just("gaussian"), "peak": NUMBERS, "width": NUMBERS},
                          optional={"height": NUMBERS}),
    st.fixed_dictionaries({"type": st.just("blackbody"), "temperature": NUMBERS}),
    st.fixed_dictionaries({"type": st.just("scale"), "of": NUMBERS, "factor": NUMBERS}),
    st.fixed_dictionaries({"type": st.just("window"), "of": NUMBERS, "min": NUMBERS, "max": NUMBERS}),
    st.fixed_dictionaries({"type": st.sampled_from(spectra.SPEC_TYPES)}, optional={"value": JSON, "of": JSON}),
    JSON)
_PATHS = list(leaf_paths(tiny_scene_dict()))


def _all_finite(value) -> bool:
    """Whether every array and number in a kernel scene (nested tuples) is finite."""
    if isinstance(value, tuple):
        return all(_all_finite(item) for item in value)
    if isinstance(value, np.ndarray) and value.dtype.kind in "fc":
        return bool(np.isfinite(value).all())
    if isinstance(value, float):
        return math.isfinite(value)
    return True


def _refused_clearly(problem: SpectralError) -> None:
    assert str(problem).strip() and "Traceback" not in str(problem)


@FUZZ
@given(changes=st.lists(st.tuples(st.sampled_from(_PATHS), JSON), min_size=1, max_size=3))
def test_the_scene_reader_loads_a_finite_scene_or_refuses_it(write_scene, changes):
    data = copy.deepcopy(tiny_scene_dict())  # it shares TINY_INDEX_TO_WORLD, which must stay as it is
    for path, value in changes:
        try:
            set_path(data, path, value)
        except (KeyError, IndexError, TypeError):  # an earlier change removed the path
            pass
    try:
        scene = load_scene(write_scene(json.loads(json.dumps(data))))
    except SpectralError as problem:
        _refused_clearly(problem)
        return
    assert _all_finite(lowering.compile_scene(scene))


@FUZZ
@given(text=st.one_of(st.text(max_size=200), st.binary(max_size=200).map(lambda raw: raw.decode("latin-1"))))
def test_any_text_as_a_scene_file_is_refused_clearly(tmp_path, text):
    path = tmp_path / "scene.json"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    with pytest.raises(SpectralError) as error:
        load_scene(path)
    _refused_clearly(error.value)


@FUZZ
@given(spec=SPECTRUM_SPECS)
def test_a_spectrum_description_gives_a_finite_spectrum_or_a_clear_error(spec):
    try:
        spectrum = spectra.from_spec(spec, name="fuzzed")
    except SpectralError as problem:
        _refused_clearly(problem)
        return
    assert np.isfinite(spectrum.values).all()


CSV_FIELD = st.one_of(NUMBERS.map(str), st.text(alphabet="0123456789.eE+-naif #,\"", max_size=8))


@FUZZ
@given(rows=st.lists(st.lists(CSV_FIELD, min_size=0, max_size=3), max_size=8),
       units=st.sampled_from(["nm", "um", "A", "mm"]))
def test_a_spectrum_csv_gives_a_finite_spectrum_or_a_clear_error(tmp_path, rows, units):
    path = tmp_path / "fuzzed.csv"
    path.write_text("\n".join(",".join(row) for row in rows), encoding="utf-8")
    try:
        spectrum = spectra.from_csv(path, units)
    except SpectralError as problem:
        _refused_clearly(problem)
        return
    assert np.isfinite(spectrum.values).all()


VOXELS = st.sampled_from([0.0, 1.0, 0.5, -1.0, np.nan, np.inf, 3e38, 1e-30])


@settings(FUZZ, max_examples=60)
@given(grids_=st.lists(st.tuples(st.sampled_from(["density", "heat", "", "density "]),
                                 st.lists(VOXELS, min_size=1, max_size=8),
                                 st.sampled_from([1.0, -2.0, 1e-3, 1e30])), min_size=1, max_size=3),
       asked=st.sampled_from([None, "density", "heat", "missing"]))
def test_the_vdb_reader_gives_a_checked_grid_or_a_clear_error(openvdb, tmp_path, grids_, asked):
    out = []
    for name, voxels, scale in grids_:
        grid = openvdb.FloatGrid()
        grid.name = name
        grid.copyFromArray(np.array(voxels, dtype=np.float32).reshape(-1, 1, 1))
        if scale != 1.0:
            grid.transform = openvdb.createLinearTransform(voxelSize=scale) if scale > 0 else \
                openvdb.createLinearTransform([[scale, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
        out.append(grid)
    path = tmp_path / "fuzzed.vdb"
    openvdb.write(str(path), out)
    try:
        grid = grids.load_grid(path, asked)
    except SpectralError as problem:
        _refused_clearly(problem)
        return
    assert np.isfinite(grid.values).all() and (grid.values >= 0).all()
    assert np.isfinite(grid.index_to_world).all() and abs(np.linalg.det(grid.index_to_world)) > 0


def _quick_render(scene, **_options) -> RenderResult:
    """Stands in for the render (the options' handling is what is fuzzed): a film of the scene's size."""
    film = Film(scene.camera.width, scene.camera.height, 1)
    film.add(0, 0, 0, np.ones((film.height, film.width, 3)), np.ones((film.height, film.width, 3)), 1)
    return RenderResult(film=film, seconds=0.1, stats=render_stats(film, 0.1, "numpy"))


OPTION_VALUES = st.one_of(st.integers(min_value=-3, max_value=3), st.sampled_from(
    ["0", "1", "-1", "2.5", "nan", "inf", "1e400", str(2**64), str(2**32 + 1), "x", ""]))
OUTPUTS = st.sampled_from(["a.exr", "a.png", "a.npy", "s.json", "sub/../a.exr", "a.exr/b.exr", "dir.exr"])


@FUZZ
@given(numbers=st.lists(st.tuples(st.sampled_from(["--spp", "--seed", "--threads", "--workers", "--tile-size",
                                                     "--timeout", "--backend"]), OPTION_VALUES), max_size=3),
       outputs=st.lists(st.tuples(st.sampled_from(["--png", "--npy", "--stats"]), OUTPUTS), max_size=3),
       out=OUTPUTS)
def test_command_line_option_combinations_render_finite_files_or_exit_1_with_a_message(
        write_scene, tmp_path_factory, monkeypatch, capsys, numbers, outputs, out):
    from addon.tracer import farm, render

    monkeypatch.setattr(render, "render", _quick_render)
    monkeypatch.setattr(farm, "render", _quick_render)
    folder = tmp_path_factory.mktemp("cli")
    (folder / "dir.exr").mkdir()
    (folder / "sub").mkdir()
    argv = ["render", str(write_scene()), "--out", str(folder / out), "--quiet"]
    for option, value in numbers:
        argv += [option, str(value)]
    for option, name in outputs:
        argv += [option, str(folder / name)]
    try:
        code = cli.main(argv)
    except SystemExit as usage:  # argparse: a value of the wrong type, an unknown choice
        assert usage.code == cli.EXIT_USAGE and "error:" in capsys.readouterr().err
        return
    err = capsys.readouterr().err
    files = sorted(path.relative_to(folder).as_posix() for path in folder.rglob("*") if path.is_file())
    if code == cli.EXIT_BAD_INPUT:
        assert err.startswith("error: ") and files == []
        return
    assert code == cli.EXIT_OK, err
    stats = [folder / name for option, name in outputs if option == "--stats"][-1:]  # the last one given counts
    for name in files:
        path = folder / name
        if stats and path.resolve() == stats[0].resolve():  # JSON, whatever its name says
            assert json.loads(path.read_text())["pixel_samples_per_second"] >= 0
        elif path.suffix == ".exr":
            assert all(np.isfinite(channel).all() for channel in image_io.read_exr(path).values())
        elif path.suffix == ".npy":
            assert np.isfinite(np.load(path)).all()
