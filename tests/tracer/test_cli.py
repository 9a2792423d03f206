"""The tracer's command line: renders a scene file to EXR/PNG/NPY/stats, validates scenes, and
reports bad input with exit code 1 and a message, leaving existing files untouched."""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import image_io

ROOT = Path(__file__).resolve().parents[2]


def run_cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "addon.tracer", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=600)


def test_render_writes_every_requested_output(write_scene, tmp_path):
    scene = write_scene()
    out = tmp_path / "result" / "image.exr"
    done = run_cli("render", scene, "--spp", 3, "--seed", 2, "--out", out, "--png", tmp_path / "image.png",
                   "--npy", tmp_path / "image.npy", "--stats", tmp_path / "stats.json", "--threads", 1)
    assert done.returncode == 0, done.stderr
    channels = image_io.read_exr(out)
    assert {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B", "ViewLayer.Combined.A",
            "ViewLayer.XYZ.X", "ViewLayer.XYZ.Y", "ViewLayer.XYZ.Z", "ViewLayer.XYZ Variance.Y"} <= set(channels)
    assert channels["ViewLayer.XYZ.Y"].shape == (6, 8)
    xyz = np.load(tmp_path / "image.npy")
    np.testing.assert_allclose(xyz[..., 1], channels["ViewLayer.XYZ.Y"], rtol=1e-6)
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["samples_per_pixel"] == 3 and stats["pixel_samples_per_second"] > 0
    np.testing.assert_allclose(stats["mean_xyz"][1], xyz[..., 1].mean(), rtol=1e-5)
    assert (tmp_path / "image.png").stat().st_size > 0
    assert "%" in done.stderr  # the progress bar


def test_spectral_exr_writes_the_bins_the_options_choose(write_scene, tmp_path):
    """--spectral-exr writes the spectral image beside the EXR, its bins from --spectrum-start/-end/-step, its
    units as the scene's lights give them; the bin options without it are a usage error."""
    from addon.tracer import spectral_film
    from addon.tracer.scene_io import load_scene

    scene = write_scene()
    spectral = tmp_path / "spectral.exr"
    done = run_cli("render", scene, "--spp", 2, "--backend", "numpy", "--out", tmp_path / "image.exr",
                   "--spectral-exr", spectral, "--spectrum-start", 400, "--spectrum-end", 700, "--spectrum-step", 20)
    assert done.returncode == 0, done.stderr
    import OpenImageIO

    image = OpenImageIO.ImageInput.open(str(spectral))
    spec = image.spec()
    image.close()
    assert [name for name in spec.channelnames if name.startswith("S0.")] == [f"S0.{nm}nm" for nm in range(410, 700, 20)]
    assert spec.getattribute("emissiveUnits") == spectral_film.radiance_units(load_scene(scene))
    channels = image_io.read_exr(spectral)
    np.testing.assert_allclose(channels["R"], image_io.read_exr(tmp_path / "image.exr")["ViewLayer.Combined.R"])
    done = run_cli("render", scene, "--out", tmp_path / "other.exr", "--spectrum-step", 5)
    assert done.returncode == 2 and "add --spectral-exr PATH" in done.stderr
    done = run_cli("render", scene, "--out", tmp_path / "other.exr", "--spectral-exr", spectral, "--spectrum-step", 7)
    assert done.returncode == 1 and "--spectral-exr: render.spectrum_step: 380–780 nm is not a whole number" in done.stderr


def test_validate_summarises_a_good_scene(write_scene):
    done = run_cli("validate", write_scene())
    assert done.returncode == 0, done.stderr
    assert "cloud" in done.stdout


def test_bad_scene_exits_1_with_a_message_and_keeps_existing_output(write_scene, scene_data, tmp_path):
    scene_data["media"][0]["albedo"] = 1.5
    scene = write_scene(scene_data)
    out = tmp_path / "image.exr"
    out.write_bytes(b"previous render")
    done = run_cli("render", scene, "--out", out)
    assert done.returncode == 1
    assert "albedo must be within [0, 1]" in done.stderr and "Traceback" not in done.stderr
    assert out.read_bytes() == b"previous render"


def test_missing_scene_file_is_reported(tmp_path):
    done = run_cli("render", tmp_path / "nowhere.json", "--out", tmp_path / "x.exr")
    assert done.returncode == 1 and "nowhere.json" in done.stderr and "Traceback" not in done.stderr


def test_the_cli_says_when_the_kernel_compiles(write_scene, tmp_path, monkeypatch, capsys):
    from addon.tracer import cli
    from addon.tracer.kernels import numba_cache

    def compiling(dispatcher, prepare, cancel=None, notice=None):
        notice(numba_cache.compiling_message())
        prepare()
        return True

    monkeypatch.setattr(numba_cache, "ready", compiling)
    assert cli.main(["render", str(write_scene()), "--out", str(tmp_path / "image.exr")]) == cli.EXIT_OK
    assert "Compiling the kernel (" in capsys.readouterr().err


def test_the_progress_bar_estimates_the_time_left_from_the_samples_done_since_its_first_report(monkeypatch):
    import io

    from addon.tracer import cli

    clock = iter([0.0, 100.0, 100.0, 100.01, 100.01, 101.0, 101.0])  # start, then elapsed and time left per report
    monkeypatch.setattr(cli.time, "perf_counter", lambda: next(clock))
    stream = io.StringIO()
    bar = cli.ProgressBar(stream, interval=0.1)
    bar(None, 0.1)  # after 100 s of compiling: no estimate yet
    bar(None, 0.11)  # 10 ms later: not shown
    bar(None, 0.2)  # 1 s for 10 %: 8 s left
    lines = stream.getvalue().split("\r")
    assert len(lines) == 3 and "left" not in lines[1] and lines[2].endswith("~  8.0s left")
    bar.notice("a line of its own")
    assert stream.getvalue().endswith("a line of its own\n")


def test_a_huge_seed_in_the_scene_is_refused_when_loading(write_scene, scene_data, tmp_path):
    scene_data["render"]["seed"] = 2**64
    done = run_cli("render", write_scene(scene_data), "--out", tmp_path / "x.exr")
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert "render.seed: must be at most 18446744073709551615, found 18446744073709551616" in done.stderr


BAD_OPTIONS = {
    "seed above 2⁶⁴ − 1": (["--seed", 2**64], "--seed: must be at most 18446744073709551615"),
    "negative seed": (["--seed", -1], "--seed: must be at least 0"),
    "no samples": (["--spp", 0], "--spp: must be at least 1, found 0"),
    "no threads": (["--threads", 0], "--threads: must be at least 1"),
    "timeout nan": (["--workers", 1, "--timeout", "nan"], "--timeout: must be a positive number of seconds, at most 86400 (a day), found nan"),
    "negative timeout": (["--workers", 1, "--timeout", -5],
                         "--timeout: must be a positive number of seconds, at most 86400 (a day), found -5"),
    "no workers": (["--workers", 0], "--workers: must be at least 1, found 0"),
    "spp beyond the Sobol points": (["--spp", 2**32 + 1], "--spp: must be at most 4294967296, found 4294967297"),
    "spp of 2⁶⁴": (["--spp", 2**64], "--spp: must be at most 4294967296"),
    "a million workers": (["--workers", 10**6], "--workers: must be at most"),
    "timeout of a year": (["--workers", 1, "--timeout", 3.2e7], "at most 86400 (a day), found 3.2e+07"),
    "png as the exr": (["--out", "{tmp}/o.png"], "o.png: the file is written as EXR, so its name must end in .exr"),
    "exr as the png": (["--png", "{tmp}/o.exr"], "o.exr: the file is written as PNG, so its name must end in .png"),
    "out is a folder": (["--out", "{tmp}/folder.exr"], "folder.exr: it is a folder"),
    "parent is a file": (["--out", "{tmp}/file.txt/o.exr"], "file.txt is a file, not a folder"),
    "in /proc": (["--out", "/proc/o.exr"], "cannot write /proc/o.exr: "),
    "png in /proc": (["--png", "/proc/o.png"], "cannot write /proc/o.png: "),
    "stats in /proc": (["--stats", "/proc/stats.json"], "cannot write /proc/stats.json: "),
    "spectral exr as a png": (["--spectral-exr", "{tmp}/s.png"], "s.png: the file is written as EXR"),
}


@pytest.mark.parametrize("case", BAD_OPTIONS)
def test_bad_options_and_unwritable_outputs_are_refused_before_rendering(write_scene, tmp_path, case):
    """Checked before the scene is even loaded: no render, exit 1, a message naming the option or the file,
    and the existing output untouched."""
    options, words = BAD_OPTIONS[case]
    (tmp_path / "folder.exr").mkdir()
    (tmp_path / "file.txt").write_text("a file")
    keep = tmp_path / "keep.exr"
    keep.write_bytes(b"previous render")
    options = [str(option).format(tmp=tmp_path) for option in options]
    if "--out" not in options:
        options += ["--out", keep]
    start = time.perf_counter()
    done = run_cli("render", write_scene(), *options)
    assert done.returncode == 1, done.stderr
    assert words in done.stderr and "Traceback" not in done.stderr
    assert "%" not in done.stderr and time.perf_counter() - start < 30  # no progress bar: nothing rendered
    assert keep.read_bytes() == b"previous render"
    assert sorted(path.name for path in tmp_path.iterdir() if path.name != "scene") == ["file.txt", "folder.exr",
                                                                                         "keep.exr"]


def test_an_unexpected_exception_is_an_internal_error_with_its_own_exit_code(write_scene, tmp_path, monkeypatch,
                                                                             capsys):
    from addon.tracer import cli, scene_io

    def broken(_path):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(scene_io, "load_scene", broken)
    assert cli.main(["render", str(write_scene()), "--out", str(tmp_path / "x.exr")]) == cli.EXIT_CRASH == 70
    stderr = capsys.readouterr().err
    assert "Traceback" in stderr and "internal error: ZeroDivisionError: a bug" in stderr
    assert "This is a bug" in stderr and "report it" in stderr
    assert not (tmp_path / "x.exr").exists()


def _same_file_cases(folder: Path) -> dict:
    """Ways for two output options to name one file (issue 30): literally, via `..`, a symbolic link and a hard
    link; each case is (the options, the file they share)."""
    (folder / "sub").mkdir()
    shared = folder / "o.exr"
    shared.write_bytes(b"previous render")
    (folder / "link.png").symlink_to(shared)
    (folder / "hard.npy").hardlink_to(shared)
    return {
        "stats on the image": (["--out", shared, "--stats", shared], shared),
        "dot-dot": (["--out", shared, "--stats", folder / "sub" / ".." / "o.exr"], shared),
        "symbolic link": (["--out", shared, "--png", folder / "link.png"], shared),
        "hard link": (["--out", shared, "--npy", folder / "hard.npy"], shared),
    }


@pytest.mark.parametrize("case", ["stats on the image", "dot-dot", "symbolic link", "hard link"])
def test_two_outputs_naming_one_file_are_refused_before_rendering(write_scene, tmp_path, case, monkeypatch, capsys):
    from addon.tracer import cli, scene_io

    options, shared = _same_file_cases(tmp_path)[case]
    monkeypatch.setattr(scene_io, "load_scene", lambda path: pytest.fail("the scene was loaded: too late"))
    assert cli.main(["render", str(write_scene()), *map(str, options)]) == cli.EXIT_BAD_INPUT
    message = capsys.readouterr().err
    assert options[0] in message and options[2] in message and "same file" in message
    assert shared.read_bytes() == b"previous render"


def test_write_all_refuses_two_outputs_of_one_file(tmp_path):
    target = tmp_path / "a.npy"
    with pytest.raises(image_io.SpectralError, match="same file"):
        image_io.write_all([image_io.npy(target, np.zeros((1, 1, 3))), image_io.npy(tmp_path / "." / "a.npy",
                                                                                  np.ones((1, 1, 3)))])
    assert not target.exists()


def test_transparent_renders_an_alpha_into_the_exr_and_the_png(write_scene, scene_data, tmp_path):
    """--transparent turns on the scene's render.transparent: the sun is the only light, so a camera ray that
    misses the cloud sees nothing and alpha is below 1 there; without it alpha is 1."""
    scene = write_scene()
    out, png = tmp_path / "image.exr", tmp_path / "image.png"
    done = run_cli("render", scene, "--spp", 4, "--out", out, "--png", png, "--transparent", "--quiet")
    assert done.returncode == 0, done.stderr
    alpha = image_io.read_exr(out)["ViewLayer.Combined.A"]
    assert alpha.min() < 0.5 and alpha.max() > 0.0
    oiio = image_io._open_image_io()
    image = oiio.ImageInput.open(str(png))
    assert image.spec().nchannels == 4
    image.close()
    done = run_cli("render", scene, "--spp", 4, "--out", out, "--quiet")
    assert done.returncode == 0, done.stderr
    np.testing.assert_allclose(image_io.read_exr(out)["ViewLayer.Combined.A"], 1.0)
