"""The viewer's HTTP server: the page, its assets, the trace streamed whole or followed live."""

from __future__ import annotations

import threading
import urllib.error
import urllib.request

import pytest

from fleet_async import Agent, AgentSpawnParams, Pose, ShapeParams
from fleet_async.viewer import TraceReader

CUBE = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def fetch(url):
    with urllib.request.urlopen(url, timeout=30) as response:
        return response.read(), response.headers


@pytest.fixture
def trace(sim, tmp_path):
    Agent.from_params(AgentSpawnParams(visual_shape=CUBE, initial_pose=Pose.from_xyz(0, 0, 1)), sim)
    sim.start_trace(tmp_path / "a <b>.fatrace")
    for _ in range(5):
        sim.step_once()
    sim.stop_trace()
    return tmp_path / "a <b>.fatrace"


def test_page_assets_and_trace(serve, trace):
    server = serve(trace)
    page, headers = fetch(server.url)
    assert headers["Content-Type"].startswith("text/html")
    assert b"a &lt;b&gt;.fatrace" in page and b"<b>.fatrace" not in page  # escaped name
    for asset in ("trace.js", "render.js", "viewer.js", "viewer.css"):
        body, _ = fetch(server.url + asset)
        assert len(body) > 1000
    body, headers = fetch(server.url + "trace")
    assert body == trace.read_bytes()
    assert headers["Content-Length"] == str(len(body)) and headers.get("X-Trace-Live") is None
    with pytest.raises(urllib.error.HTTPError) as err:
        fetch(server.url + "nothing-here")
    assert err.value.code == 404


def test_follow_streams_a_growing_trace_until_its_end_record(serve, sim, tmp_path):
    Agent.from_params(AgentSpawnParams(visual_shape=CUBE, initial_pose=Pose.from_xyz(0, 0, 1)), sim)
    path = tmp_path / "live.fatrace"
    writer = sim.start_trace(path, flush_seconds=1e-9)  # every frame reaches the file at once
    sim.step_once()
    server = serve(path, follow=True)
    got: dict[str, object] = {}

    def read() -> None:
        got["body"], got["headers"] = fetch(server.url + "trace")

    reader = threading.Thread(target=read)
    reader.start()
    for _ in range(10):  # the run goes on while the page is reading
        sim.step_once()
    assert writer.is_tracing
    sim.stop_trace()
    reader.join(timeout=30)
    assert not reader.is_alive()
    assert got["headers"]["X-Trace-Live"] == "1"  # type: ignore[index]
    assert got["body"] == path.read_bytes()
    assert TraceReader(path).frame_count == 12
