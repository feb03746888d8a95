"""What the viewer server guards against: idle sockets, DNS rebinding, a swapped trace path;
what it says: its true address, and when a followed trace stops growing."""

from __future__ import annotations

import http.client
import os
import socket
import threading
import time

import pytest

from fleet_async import Agent, AgentSpawnParams, Pose, ShapeParams
from fleet_async.cli.view import open_viewer
from fleet_async.viewer.server import ViewerServer

CUBE = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


@pytest.fixture
def trace(sim, tmp_path):
    Agent.from_params(AgentSpawnParams(visual_shape=CUBE, initial_pose=Pose.from_xyz(0, 0, 1)), sim)
    sim.start_trace(tmp_path / "t.fatrace")
    for _ in range(3):
        sim.step_once()
    sim.stop_trace()
    return tmp_path / "t.fatrace"


@pytest.fixture
def started():
    servers: list[ViewerServer] = []

    def start(path, **kwargs) -> ViewerServer:
        server = ViewerServer(path, port=0, **kwargs)
        server.start_background()
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.stop()


def get(server: ViewerServer, path: str, host: str | None = None) -> tuple[int, bytes]:
    port = server.listening[1]
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    headers = {} if host is None else {"Host": host}
    conn.request("GET", path, headers=headers)
    response = conn.getresponse()
    body = response.read()
    conn.close()
    return response.status, body


def test_an_idle_connection_is_closed(started, trace):
    server = started(trace, timeout=0.5)
    with socket.create_connection(("127.0.0.1", server.listening[1])) as idle:
        idle.settimeout(30)  # the test's own guard; the server's timeout is 0.5 s
        assert idle.recv(100) == b""  # closed by the server, not by this timeout


def test_connections_past_the_cap_are_answered_503(started, trace):
    server = started(trace, timeout=30, max_connections=3)
    port = server.listening[1]
    idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(3)]
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:  # until the three hold their threads
            if sum(t.name.startswith("Thread-") for t in threading.enumerate()) >= 3:
                break
            time.sleep(0.01)
        with socket.create_connection(("127.0.0.1", port)) as extra:
            extra.settimeout(30)
            assert extra.recv(100).startswith(b"HTTP/1.0 503")
        before = threading.active_count()
        for _ in range(20):
            with socket.create_connection(("127.0.0.1", port)) as extra:
                extra.settimeout(30)
                extra.recv(100)
        assert threading.active_count() <= before
    finally:
        for s in idle:
            s.close()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # the slots are free again
        try:
            if get(server, "/")[0] == 200:
                break
        except OSError:
            pass
        time.sleep(0.05)
    assert get(server, "/")[0] == 200


def test_a_foreign_host_header_is_refused(started, trace):
    server = started(trace)
    port = server.listening[1]
    assert get(server, "/", host="attacker.example")[0] == 403
    assert get(server, "/trace", host=f"rebind.attacker.example:{port}")[0] == 403
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", "localhost", f"[::1]:{port}"):
        assert get(server, "/", host=host)[0] == 200, host
    assert get(server, "/", host=f"{socket.gethostname()}:{port}")[0] == 200


def test_the_trace_is_the_file_opened_at_start(started, trace, tmp_path):
    server = started(trace)
    original = trace.read_bytes()
    secret = tmp_path / "secret.txt"
    secret.write_text("not for the page\n")
    trace.unlink()
    os.symlink(secret, trace)  # swapped after the server started
    status, body = get(server, "/trace")
    assert status == 200 and body == original


def test_every_interface_prints_a_true_address_with_a_warning(trace, capsys):
    server = ViewerServer(trace, host="0.0.0.0", port=0)
    try:
        open_viewer(server, no_browser=True)
        out, err = capsys.readouterr()
        port = server.listening[1]
        assert f"every interface (0.0.0.0:{port})" in out and server.public_url in out
        assert "fleet-async: warning: the viewer listens on 0.0.0.0" in err
        assert "anyone who can reach this machine" in err
    finally:
        server.server_close()
    local = ViewerServer(trace, port=0)
    try:
        open_viewer(local, no_browser=True)
        out, err = capsys.readouterr()
        assert local.public_url is None and local.url in out and err == ""
    finally:
        local.server_close()


def test_follow_says_when_the_writer_stopped(started, sim, tmp_path):
    Agent.from_params(AgentSpawnParams(visual_shape=CUBE, initial_pose=Pose.from_xyz(0, 0, 1)), sim)
    path = tmp_path / "dead.fatrace"
    writer = sim.start_trace(path, flush_seconds=1e-9)
    sim.step_once()
    writer.flush()  # then the "run" stops writing without an end record
    notices: list[str] = []
    heard = threading.Event()

    def notice(message: str) -> None:
        notices.append(message)
        heard.set()

    server = started(path, follow=True, stale_after=0.2, notice=notice)
    with socket.create_connection(("127.0.0.1", server.listening[1])) as page:
        page.sendall(b"GET /trace HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
        assert heard.wait(30)
    assert len(notices) == 1
    assert str(path) in notices[0] and "has not grown for 0.2 s and has no end record" in notices[0]
    sim.stop_trace()
