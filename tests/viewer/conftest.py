"""Fixtures for the viewer: recorded traces, a server, and headless Chromium.

Browser tests need playwright and Debian's chromium. Without them they skip with the reason,
except in CI (``CI`` set) or with ``FLEET_ASYNC_REQUIRE_BROWSER=1``, where a missing browser
fails the test: the browser tests must run there.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from fleet_async.cli.run import load_scenario
from fleet_async.viewer.server import ViewerServer

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def browser_required() -> bool:
    """Whether a missing browser is a failure here (CI, or asked for)."""
    return bool(os.environ.get("CI")) or os.environ.get("FLEET_ASYNC_REQUIRE_BROWSER") == "1"


def _no_browser(reason: str) -> None:
    if browser_required():
        pytest.fail(f"{reason} (browser tests are required: CI or FLEET_ASYNC_REQUIRE_BROWSER=1)")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def browser_page() -> Iterator[Any]:
    """One headless Chromium page per test module (tests navigate it). Per module, not per
    session: the sync API keeps its event loop running on this thread while open, and tests
    that run missions (anyio.run) after the viewer tests could not start theirs."""
    try:
        import playwright.sync_api  # noqa: F401  # only checking that it is installed
    except ImportError:
        _no_browser('playwright is not installed: python -m pip install -e ".[viewer-test]"')
    from fleet_async.viewer.browser import chromium_path, launch_chromium

    if chromium_path() is None:
        _no_browser("no Chromium found (/usr/bin/chromium): apt-get install chromium")
    with launch_chromium(viewport=(1200, 760)) as page:
        yield page


def record_scenario(path: Path, scenario: str, steps: int) -> Path:
    """Run an example scenario headless for ``steps`` steps with a trace; return the trace."""
    sim = load_scenario(EXAMPLES / scenario, gui_on=False, rtf=0.0)  # headless everywhere
    try:
        sim.start_trace(path)
        for _ in range(steps):
            sim.step_once()
    finally:
        sim.close()
    return path


@pytest.fixture(scope="session")
def pick_drop_trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """pick_drop.yaml, 30 s (300 steps) traced every step."""
    path = tmp_path_factory.mktemp("traces") / "pick_drop.fatrace"
    return record_scenario(path, "pick_drop.yaml", 300)


@pytest.fixture
def serve() -> Iterator[Any]:
    """``serve(path, follow=False)`` starts a viewer server; all are stopped afterwards."""
    servers: list[ViewerServer] = []

    def start(path: Path, follow: bool = False) -> ViewerServer:
        server = ViewerServer(path, port=0, follow=follow)
        server.start_background()
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.stop()
