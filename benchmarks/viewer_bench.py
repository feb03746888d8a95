"""Viewer frame rate: the replay page playing a 10,000-robot trace in headless Chromium.

Records a trace of ``fleet_async.bench``'s workload (N robots, half of them driving; a frame
every step), serves it with the viewer's own server, opens the page in headless Chromium (the
system's ``/usr/bin/chromium``, driven by playwright), waits until the trace has loaded, then
plays it in a loop at a speed where every animation frame shows a new trace frame (so every
frame uploads fresh poses to the GPU) and reads the page's own requestAnimationFrame
timestamps. Reported: frames per second over the measured window, and the page's draw time
per frame (median and 95th percentile, ms).

Needs: pip install "fleet-async[viewer-test]" and Debian's chromium (apt-get install chromium).
Run:  python benchmarks/viewer_bench.py [--n 10000] [--steps 300] [--seconds 10]
      [--size 1280x800] [--renderer auto|canvas2d|webgl2] [--trace FILE] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time

from fleet_async.bench import bench_params, set_goals, spawn_fleet
from fleet_async.core import MultiRobotSimulationCore
from fleet_async.viewer.browser import CHROMIUM, launch_chromium
from fleet_async.viewer.server import ViewerServer


def record(path: str, n: int, steps: int) -> None:
    """Record ``steps`` steps of the workload with N robots to ``path``."""
    with MultiRobotSimulationCore(bench_params()) as sim:
        agents = spawn_fleet(sim, n)
        set_goals(agents, n)
        sim.start_trace(path)
        for _ in range(steps):
            sim.step_once()


def measure(path: str, seconds: float, size: tuple[int, int], renderer: str) -> dict[str, float]:
    server = ViewerServer(path)
    server.start_background()
    try:
        with launch_chromium(viewport=size) as page:
            query = f"?loop=1&renderer={renderer}"
            t0 = time.perf_counter()
            page.goto(server.url + query)
            page.wait_for_function(
                "['ready', 'error'].includes(document.getElementById('app').dataset.state)",
                timeout=300_000,
            )
            load_s = time.perf_counter() - t0
            state = page.evaluate("window.viewer.state()")
            if state["error"]:
                raise SystemExit(f"viewer error: {state['error']}")
            dt = page.evaluate("window.viewer.data.timestep")
            # About one trace frame per animation frame at 60 Hz.
            page.evaluate(f"window.viewer.setSpeed({dt * 60}); window.viewer.play()")
            page.wait_for_timeout(1000)  # warm-up: shaders, first uploads
            page.evaluate("window.viewer.resetStats()")
            page.wait_for_timeout(int(seconds * 1000))
            stats = page.evaluate("window.viewer.stats()")
            state = page.evaluate("window.viewer.state()")
    finally:
        server.stop()
    times = stats["times"]
    fps = (len(times) - 1) / ((times[-1] - times[0]) / 1000.0) if len(times) > 1 else 0.0
    draw = sorted(stats["drawMs"])
    return {
        "fps": fps,
        "animation_frames": len(times),
        "draw_ms_median": statistics.median(draw) if draw else 0.0,
        "draw_ms_p95": draw[int(0.95 * (len(draw) - 1))] if draw else 0.0,
        "load_s": load_s,
        "renderer": state["renderer"],
        "bodies": state["bodies"],
        "frames": state["frames"],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, default=10000, help="robots (default 10000)")
    parser.add_argument("--steps", type=int, default=300, help="steps recorded (default 300)")
    parser.add_argument("--seconds", type=float, default=10.0, help="measured window (s)")
    parser.add_argument("--size", default="1280x800", help="viewport WxH (default 1280x800)")
    parser.add_argument(
        "--renderer",
        choices=("auto", "canvas2d", "webgl2"),
        default="auto",
        help="the page's choice (auto: WebGL2 on a hardware GPU, else Canvas2D), or force one",
    )
    parser.add_argument("--trace", help="measure this trace instead of recording one")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if not os.path.exists(CHROMIUM):
        raise SystemExit(f"{CHROMIUM} not found: apt-get install chromium")
    width, height = (int(v) for v in args.size.lower().split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        path = args.trace or os.path.join(tmp, "viewer_bench.fatrace")
        if not args.trace:
            record(path, args.n, args.steps)
        result = measure(path, args.seconds, (width, height), args.renderer)
    result["n"] = args.n if not args.trace else result["bodies"]
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"{result['bodies']} bodies, {result['frames']} trace frames, {width}x{height}, "
            f"{result['renderer']}: {result['fps']:.1f} fps over {args.seconds:.0f} s "
            f"({result['animation_frames']} animation frames); draw "
            f"{result['draw_ms_median']:.2f} ms median, {result['draw_ms_p95']:.2f} ms p95; "
            f"trace loaded in {result['load_s']:.1f} s"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
