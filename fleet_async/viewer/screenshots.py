"""Screenshots of the viewer explaining a robot's day, for the docs (and the test that
checks what they show).

``python -m fleet_async.viewer.screenshots docs/images`` runs the warehouse example's shift
headless with a trace, opens the trace in headless Chromium (Debian's ``chromium``, through
playwright: the ``viewer-test`` extra), selects ``picker_0`` and saves the page at three
moments of its first order: on its way to the tote, carrying it to the station, and dropping
it there (``viewer_picking.png``, ``viewer_carrying.png``, ``viewer_dropping.png``).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import tempfile
from pathlib import Path
from typing import Any

from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.viewer.browser import launch_chromium
from fleet_async.viewer.server import ViewerServer

__all__ = ["MOMENTS", "Screenshots", "main", "record_warehouse", "take_screenshots"]

WAREHOUSE = Path(__file__).resolve().parents[1].parent / "examples" / "scenarios" / "warehouse.yaml"
ROBOT = "picker_0"
MOMENTS = (("picking", 9.0), ("carrying", 25.0), ("dropping", 40.0))
"""(name, sim time in s) of each screenshot: picker_0's first order, from tote to station."""
_READY = "['ready', 'error'].includes(document.getElementById('app').dataset.state)"


@dataclasses.dataclass
class Screenshots:
    """What :func:`take_screenshots` saw.

    Attributes:
        files: The PNG files written, in MOMENTS order.
        robot_id: The object id of the robot selected.
        timeline: Its timeline rows as the page lists them (kind, t, t1, text).
        doing: The panel's "now ..." line at each moment.
    """

    files: list[Path]
    robot_id: int
    timeline: list[dict[str, Any]]
    doing: list[str]


def _warehouse_path() -> Path:
    installed = Path(__file__).resolve().parents[1] / "examples" / "scenarios" / "warehouse.yaml"
    return installed if installed.exists() else WAREHOUSE


def record_warehouse(trace: Path) -> Path:
    """Run the warehouse shift (its missions, headless, unpaced) with a trace to ``trace``."""
    from fleet_async.core.base.config_utils import load_yaml_config
    from fleet_async.scenario_runner import run_scenario

    scenario = _warehouse_path()
    config = load_yaml_config(scenario)
    config["simulation"].update(gui=False, target_rtf=0.0)
    config["trace"] = str(trace)
    sim = MultiRobotSimulationCore.from_dict(config, source=str(scenario), base_dir=scenario.parent)
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # the missions' log
            run_scenario(sim)
    finally:
        sim.close()
    return trace


def take_screenshots(
    trace: Path, out_dir: Path, page: Any = None, size: tuple[int, int] = (1400, 860)
) -> Screenshots:
    """Open ``trace`` in the viewer, select ``picker_0`` and save one PNG per moment.

    Args:
        trace: A trace of the warehouse shift (:func:`record_warehouse`).
        out_dir: Where the PNG files go (created if missing).
        page: A playwright page to use (a test's); None starts headless Chromium.
        size: The page's size in CSS pixels.

    Raises:
        ImportError, FileNotFoundError: without playwright or Chromium (from launch_chromium).
        RuntimeError: if the page reports an error or the trace has no ``picker_0``.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    server = ViewerServer(trace, port=0)
    server.start_background()
    try:
        if page is not None:
            page.set_viewport_size({"width": size[0], "height": size[1]})
            return _shoot(page, server.url, trace, out_dir)
        with launch_chromium(viewport=size) as own:
            return _shoot(own, server.url, trace, out_dir)
    finally:
        server.stop()


def _shoot(page: Any, url: str, trace: Path, out_dir: Path) -> Screenshots:
    page.goto(url)
    page.wait_for_function(_READY, timeout=120_000)
    error = page.evaluate("viewer.state().error")
    if error:
        raise RuntimeError(f"the viewer could not show {trace}: {error}")
    robot = page.evaluate(
        f"[...viewer.data.bodies.values()].filter((b) => b.name === {ROBOT!r}).map((b) => b.id)[0]"
    )
    if robot is None:
        raise RuntimeError(f"{trace}: no body called {ROBOT!r}")
    page.evaluate(f"viewer.select({robot}); viewer.setLabels(true)")
    files, doing = [], []
    for name, t in MOMENTS:
        page.evaluate(f"viewer.seek({t})")
        page.wait_for_function(
            f"Math.abs(Number(document.getElementById('app').dataset.simTime) - {t}) < 0.2"
        )
        doing.append(page.inner_text("#sel-doing"))
        path = out_dir / f"viewer_{name}.png"
        page.screenshot(path=str(path))
        files.append(path)
    timeline = page.evaluate("viewer.timeline()")
    page.evaluate("viewer.setLabels(false); viewer.select(null)")
    return Screenshots(files, int(robot), timeline, doing)


def main(argv: list[str] | None = None) -> int:
    """The command: record the warehouse trace and save the screenshots into OUT_DIR."""
    parser = argparse.ArgumentParser(
        prog="python -m fleet_async.viewer.screenshots", description=__doc__.splitlines()[0]
    )
    parser.add_argument("out_dir", type=Path, help="where the PNG files go (e.g. docs/images)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        trace = record_warehouse(Path(tmp) / "warehouse.fatrace")
        shots = take_screenshots(trace, args.out_dir)
    for path, line in zip(shots.files, shots.doing, strict=True):
        print(f"{path}: {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
