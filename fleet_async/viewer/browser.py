"""Driving the system's headless Chromium with playwright (tests, benchmarks, screenshots).

Uses Debian's ``chromium`` package (``/usr/bin/chromium``, or ``$FLEET_ASYNC_CHROMIUM``);
it never downloads a browser (no ``playwright install``). Needs the ``viewer-test`` extra:
``python -m pip install -e ".[viewer-test]"``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["CHROMIUM", "CHROMIUM_FLAGS", "chromium_path", "launch_chromium"]

CHROMIUM = "/usr/bin/chromium"
"""Where Debian's chromium package puts the browser."""
CHROMIUM_FLAGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)
"""Flags that work headless on a machine without a GPU or a display (WebGL2 runs in
software)."""


def chromium_path() -> str | None:
    """The Chromium executable to use, or None if there is none."""
    configured = os.environ.get("FLEET_ASYNC_CHROMIUM")
    if configured:
        return configured if os.path.exists(configured) else None
    if os.path.exists(CHROMIUM):
        return CHROMIUM
    return shutil.which("chromium") or shutil.which("chromium-browser")


@contextmanager
def launch_chromium(viewport: tuple[int, int] = (1280, 800)) -> Iterator[Any]:
    """Start headless Chromium with a fresh profile; yield a playwright page; close both.

    Raises:
        ImportError: if playwright is not installed, with the install command.
        FileNotFoundError: if there is no Chromium, with the install command.
    """
    try:
        from playwright.sync_api import sync_playwright  # an optional extra
    except ImportError as exc:
        raise ImportError(
            'driving Chromium needs playwright: python -m pip install -e ".[viewer-test]"'
        ) from exc
    executable = chromium_path()
    if executable is None:
        raise FileNotFoundError(
            f"no Chromium at {CHROMIUM} (nor chromium on PATH, nor $FLEET_ASYNC_CHROMIUM): "
            "apt-get install chromium"
        )
    with (
        tempfile.TemporaryDirectory(prefix="fleet-async-chromium-") as profile,
        sync_playwright() as pw,
    ):
        context = pw.chromium.launch_persistent_context(
            profile,
            executable_path=executable,
            headless=True,
            args=[*CHROMIUM_FLAGS],
            viewport={"width": viewport[0], "height": viewport[1]},
        )
        try:
            yield context.pages[0] if context.pages else context.new_page()
        finally:
            context.close()
