"""Writing recorded frames to files: animated GIF (Pillow) and MP4 (imageio with PyAV).

Both packages are optional (the ``record`` extra); a writer checks for its package when it is
created and raises an ImportError that says what to install.
"""

from __future__ import annotations

import importlib
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["INSTALL_HINT", "WRITERS", "GifWriter", "Mp4Writer", "import_or_explain"]

INSTALL_HINT = (
    'python -m pip install Pillow "imageio[pyav]" (or, in a fleet_async source checkout, '
    'python -m pip install -e ".[record]")'
)


def import_or_explain(module: str, what: str) -> Any:
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(
            f"{what}, but the package providing {module!r} is not installed; "
            f"install the recording extras with: {INSTALL_HINT}"
        ) from exc


class GifWriter:
    """Collects frames and writes a looping GIF on close (GIFs cannot be appended to).

    Frames are turned into palette images as they arrive, on the palette of the first frame
    (a median cut of its colours; later colours take the nearest entry), and kept
    zlib-compressed: converting and compressing a frame costs a few ms where Pillow's own
    conversion of an RGB frame at save time costs ~80 ms at 800 x 600, and a frame of a
    top-down recording is kept in ~10 kB instead of 1.4 MB.
    """

    def __init__(self, path: Path, fps: int) -> None:
        self._image = import_or_explain("PIL.Image", "recording a .gif needs Pillow")
        self._path = path
        self._fps = fps
        self._palette: Any = None
        self._size: tuple[int, int] = (0, 0)
        self._frames: list[tuple[bytes, int]] = []

    def add(self, frame: np.ndarray, repeat: int) -> None:
        image = self._image.fromarray(frame)
        pil = self._image
        if self._palette is None:
            self._palette = image.quantize(
                colors=255, method=pil.Quantize.MEDIANCUT, dither=pil.Dither.NONE
            )
            self._size = image.size
        indexed = image.quantize(palette=self._palette, dither=pil.Dither.NONE)
        self._frames.append((zlib.compress(indexed.tobytes(), 1), repeat))

    def _images(self) -> Iterator[Any]:
        palette = self._palette.getpalette()
        for data, _ in self._frames:
            image = self._image.frombytes("P", self._size, zlib.decompress(data))
            image.putpalette(palette)
            yield image

    def close(self) -> None:
        if not self._frames:
            return
        # Delays are whole centiseconds; taking differences of the cumulative slot times keeps
        # the total playback time exact (e.g. 15 fps -> 6, 7, 7, 6, 7, 7, ... cs).
        durations_ms, slot = [], 0
        for _, repeat in self._frames:
            cs = ((slot + repeat) * 100) // self._fps - (slot * 100) // self._fps
            durations_ms.append(10 * cs)
            slot += repeat
        images = self._images()
        next(images).save(
            self._path,
            format="GIF",
            save_all=True,
            append_images=images,
            duration=durations_ms,
            loop=0,
        )


class Mp4Writer:
    """Streams frames to an H.264 MP4 file through imageio's PyAV plugin."""

    def __init__(self, path: Path, fps: int) -> None:
        what = "recording an .mp4 needs imageio with its pyav plugin"
        iio = import_or_explain("imageio.v3", what)
        import_or_explain("av", what)
        self._open: Callable[[], Any] = lambda: iio.imopen(path, "w", plugin="pyav")
        self._fps = fps
        self._file: Any = None

    def add(self, frame: np.ndarray, repeat: int) -> None:
        if self._file is None:
            self._file = self._open()
            self._file.init_video_stream("libx264", fps=self._fps)
        for _ in range(repeat):
            self._file.write_frame(frame)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()


WRITERS: dict[str, Callable[[Path, int], GifWriter | Mp4Writer]] = {
    ".gif": GifWriter,
    ".mp4": Mp4Writer,
}
