"""The command line's frame and size options, read as Blender's own command line reads them: frame lists
(`1-250`, `1,3,5-7`), output paths with `#` frame-number placeholders (`out/frame_####.exr`), and
`--resolution WxH`. Pure text → values; each bad value is a SpectralError naming the option."""

import re
from pathlib import Path

from ..tracer.errors import SpectralError

_FRAME_ITEM = re.compile(r"\s*(-?\d+)\s*(?:-\s*(-?\d+)\s*)?")
_RESOLUTION = re.compile(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*")
_HASHES = re.compile(r"#+")


def parse_frames(text: str, limits: tuple[int, int]) -> list[int]:
    """Frames in the order given, each once: `1-250` is 1 to 250 inclusive, items are separated by commas;
    every frame within `limits` (Blender's, inclusive)."""
    option, frames, seen = "--frames", [], set()
    for item in text.split(","):
        match = _FRAME_ITEM.fullmatch(item)
        if match is None:
            raise SpectralError(f"{option}: {item.strip()!r} is neither a frame nor a range FIRST-LAST "
                                f"(e.g. 1-250 or 1,3,5-7), in {text!r}")
        first = int(match[1])
        last = first if match[2] is None else int(match[2])
        if last < first:
            raise SpectralError(f"{option}: the range {item.strip()} runs backwards; write {last}-{first}")
        for end in (first, last):
            if not limits[0] <= end <= limits[1]:
                raise SpectralError(f"{option}: Blender's frames run from {limits[0]} to {limits[1]}, found {end}")
        for frame in range(first, last + 1):
            if frame not in seen:
                seen.add(frame)
                frames.append(frame)
    return frames


def frame_path(path: Path, frame: int) -> Path:
    """`path` with its last run of `#` replaced by the frame number, zero-padded to the run's length
    (`frame_####.exr`, frame 7: `frame_0007.exr`), as Blender names animation frames; unchanged without `#`."""
    runs = list(_HASHES.finditer(str(path)))
    if not runs:
        return path
    run, text = runs[-1], str(path)
    return Path(f"{text[:run.start()]}{frame:0{len(run[0])}d}{text[run.end():]}")


def check_frame_paths(paths: dict[str, Path | None], frames: list[int]) -> None:
    """More than one frame needs a `#` in every output path (else each frame would overwrite the last)."""
    if len(frames) < 2:
        return
    for option, path in paths.items():
        if path is not None and "#" not in str(path):
            raise SpectralError(f"{option}: {len(frames)} frames need a '#' in the file name where the frame "
                                f"number goes (e.g. {Path(path).with_stem(Path(path).stem + '_####')})")


def parse_resolution(text: str, limits: tuple[int, int]) -> tuple[int, int]:
    """`WxH` → (width, height), each within `limits` (Blender's, inclusive)."""
    match = _RESOLUTION.fullmatch(text)
    if match is None:
        raise SpectralError(f"--resolution: write it as WIDTHxHEIGHT in pixels (e.g. 1920x1080), found {text!r}")
    size = int(match[1]), int(match[2])
    low, high = limits
    if not all(low <= side <= high for side in size):
        raise SpectralError(f"--resolution: each side must be from {low} to {high} pixels, as in Blender, "
                            f"found {text.strip()}")
    return size
