"""Map readers: ROS map_server occupancy grids (YAML + PGM / PNG) and MovingAI ``.map`` /
``.scen`` benchmark files, each into an :class:`OccupancyGrid`.

map_server YAML keys: ``image`` (relative to the YAML file), ``resolution`` (m per cell),
``origin`` ``[x, y, yaw]`` (yaw 0 only), ``negate`` (0 / 1), ``occupied_thresh``,
``free_thresh`` and ``mode`` (``trinary``, ``scale`` or ``raw``). A pixel's occupancy is
``(255 - v) / 255`` (``v / 255`` with ``negate``); above ``occupied_thresh`` it is occupied, below
``free_thresh`` free, and in between unknown, which counts as free (``raw`` mode: a value of
100 or more is occupied). PGM (P2 / P5) is read here; PNG needs Pillow (``fleet-async[record]``).

MovingAI ``.map`` (``type octile``, ``height``, ``width``, ``map`` and the rows): ``@``, ``O``,
``T`` and ``W`` are obstacles, ``.``, ``G`` and ``S`` free. MovingAI's cell (x, y) (column x of
text row y) becomes world (x + 0.5, y + 0.5) * resolution, so ``.scen`` coordinates are used
as they are (the map is then mirrored top to bottom compared to its text).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fleet_async.core.base.config_utils import load_yaml_config
from fleet_async.core.maps.grid import OccupancyGrid

__all__ = ["MovingAiTask", "read_map_server", "read_movingai_map", "read_movingai_scen", "read_pgm"]

_MAP_SERVER_KEYS = {
    "image",
    "resolution",
    "origin",
    "negate",
    "occupied_thresh",
    "free_thresh",
    "mode",
}
_OBSTACLES = frozenset("@OTW")
_FREE = frozenset(".GS")


@dataclass(frozen=True)
class MovingAiTask:
    """One line of a ``.scen`` file: a start and a goal cell (column x, row y)."""

    bucket: int
    start: tuple[int, int]
    goal: tuple[int, int]
    optimal_length: float


def _tokens(data: bytes) -> tuple[list[bytes], int]:
    """The header tokens of a PGM (magic, width, height, maxval) and where the pixels start."""
    tokens: list[bytes] = []
    i = 0
    while len(tokens) < 4:
        while i < len(data) and data[i : i + 1].isspace():
            i += 1
        if data[i : i + 1] == b"#":
            while i < len(data) and data[i : i + 1] not in (b"\n", b"\r"):
                i += 1
            continue
        j = i
        while j < len(data) and not data[j : j + 1].isspace():
            j += 1
        if j == i:
            raise ValueError("truncated PGM header")
        tokens.append(data[i:j])
        i = j
    return tokens, i + 1  # one whitespace byte separates the header from binary pixels


def read_pgm(path: str | os.PathLike[str]) -> np.ndarray:
    """A PGM image (P2 ASCII or P5 binary) as (rows, cols) ints, top row first.

    Raises:
        ValueError: naming the file, for anything but a valid PGM.
    """
    data = Path(path).read_bytes()
    try:
        (magic, w, h, maxval), start = _tokens(data)
        width, height, top = int(w), int(h), int(maxval)
        if magic == b"P5":
            dtype = np.dtype(">u2") if top > 255 else np.dtype(np.uint8)
            pixels = np.frombuffer(data, dtype=dtype, count=width * height, offset=start)
        elif magic == b"P2":
            pixels = np.array(data[start - 1 :].split()[: width * height], dtype=np.int64)
        else:
            raise ValueError(f"not a PGM (magic {magic!r}; P2 and P5 are read)")
        if pixels.size != width * height:
            raise ValueError(f"{pixels.size} pixels for {width} x {height}")
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    return pixels.reshape(height, width).astype(np.int64) * 255 // max(top, 1)


def _read_image(path: Path) -> np.ndarray:
    if path.suffix.lower() == ".pgm":
        return read_pgm(path)
    try:
        from PIL import Image
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError(
            f"{path}: reading {path.suffix} maps needs Pillow: pip install 'fleet-async[record]'"
        ) from exc
    with Image.open(path) as image:
        return np.asarray(image.convert("L"), dtype=np.int64)


def _check(value: Any, key: str, where: str, low: float = -np.inf, high: float = np.inf) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and low <= value <= high
    if not ok:
        raise ValueError(f"{where}: {key}: expected a number in [{low}, {high}], got {value!r}")
    return float(value)


def read_map_server(path: str | os.PathLike[str]) -> OccupancyGrid:
    """An occupancy grid from a map_server YAML file and its image (see the module doc).

    Raises:
        FileNotFoundError: for a missing YAML file or image.
        ValueError: for a bad key or value, naming the file, the key and the value.
    """
    yaml_path = Path(path)
    where = str(yaml_path)
    meta = load_yaml_config(yaml_path, allow_empty=False)
    unknown = sorted(set(meta) - _MAP_SERVER_KEYS)
    if unknown:
        raise ValueError(
            f"{where}: unknown key {unknown[0]!r} (expected {sorted(_MAP_SERVER_KEYS)})"
        )
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            raise ValueError(f"{where}: missing key {key!r}")
    resolution = _check(meta["resolution"], "resolution", where, 1e-9)
    origin = meta["origin"]
    if not (isinstance(origin, list) and len(origin) in (2, 3)):
        raise ValueError(f"{where}: origin: expected [x, y, yaw], got {origin!r}")
    ox, oy = (_check(v, "origin", where) for v in origin[:2])
    if len(origin) == 3 and _check(origin[2], "origin", where) != 0.0:
        raise ValueError(f"{where}: origin: a rotated map (yaw {origin[2]!r}) is not supported")
    negate = meta.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise ValueError(f"{where}: negate: expected 0 or 1, got {negate!r}")
    occupied_thresh = _check(meta.get("occupied_thresh", 0.65), "occupied_thresh", where, 0, 1)
    _check(meta.get("free_thresh", 0.196), "free_thresh", where, 0, 1)
    mode = meta.get("mode", "trinary")
    if mode not in ("trinary", "scale", "raw"):
        raise ValueError(f"{where}: mode: expected trinary, scale or raw, got {mode!r}")
    image = meta["image"]
    if not isinstance(image, str):
        raise ValueError(f"{where}: image: expected a file name, got {image!r}")
    image_path = (yaml_path.parent / image).resolve()
    if not image_path.is_file():
        raise FileNotFoundError(f"{where}: image: no file {image_path}")
    pixels = _read_image(image_path)
    if mode == "raw":
        occupied = pixels >= 100
    else:
        p = pixels / 255.0 if negate else (255 - pixels) / 255.0
        occupied = p > occupied_thresh
    return OccupancyGrid(occupied[::-1].copy(), resolution, (ox, oy))


def read_movingai_map(path: str | os.PathLike[str], resolution: float = 1.0) -> OccupancyGrid:
    """A MovingAI ``.map`` file as an occupancy grid of ``resolution`` m cells.

    Raises:
        ValueError: for a malformed file, naming it and the line.
    """
    where = str(path)
    lines = Path(path).read_text().splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines) and lines[i].strip() != "map":
        key, _, value = lines[i].strip().partition(" ")
        if key:
            header[key] = value.strip()
        i += 1
    try:
        height, width = int(header["height"]), int(header["width"])
    except (KeyError, ValueError):
        raise ValueError(f"{where}: expected 'height N' and 'width N' before 'map'") from None
    rows = lines[i + 1 : i + 1 + height]
    if len(rows) != height:
        raise ValueError(f"{where}: {len(rows)} map rows for height {height}")
    occupied = np.zeros((height, width), dtype=bool)
    for y, row in enumerate(rows):
        text = row.rstrip("\r\n")
        if len(text) != width:
            raise ValueError(f"{where}:{i + 2 + y}: {len(text)} cells for width {width}")
        bad = set(text) - _OBSTACLES - _FREE
        if bad:
            raise ValueError(f"{where}:{i + 2 + y}: unknown terrain {sorted(bad)[0]!r}")
        occupied[y] = [c in _OBSTACLES for c in text]
    return OccupancyGrid(occupied, resolution, (0.0, 0.0))


def read_movingai_scen(path: str | os.PathLike[str]) -> list[MovingAiTask]:
    """The start / goal tasks of a MovingAI ``.scen`` file, in file order.

    Raises:
        ValueError: for a malformed line, naming the file and the line.
    """
    where = str(path)
    tasks = []
    for n, line in enumerate(Path(path).read_text().splitlines(), start=1):
        if not line.strip() or line.startswith("version"):
            continue
        parts = line.split("\t") if "\t" in line else line.split()
        try:
            bucket, _map, _w, _h, sx, sy, gx, gy, opt = parts
            tasks.append(
                MovingAiTask(int(bucket), (int(sx), int(sy)), (int(gx), int(gy)), float(opt))
            )
        except ValueError:
            raise ValueError(
                f"{where}:{n}: expected 'bucket map width height sx sy gx gy length'"
            ) from None
    return tasks
