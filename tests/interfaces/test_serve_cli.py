"""``fleet-async serve`` as a user runs it: vehicles online, and a clean stop on a signal."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.interfaces.conftest import TIMEOUT, Sniffer

REPO = Path(__file__).resolve().parents[2]
SCENARIO = REPO / "examples" / "scenarios" / "served_fleet.yaml"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_serve_publishes_online_then_offline_on_a_signal(
    signum: int, broker_url: str, manufacturer: str, sniffer: Sniffer
) -> None:
    command = [sys.executable, "-m", "fleet_async", "serve", str(SCENARIO), "--broker",
               broker_url, "--manufacturer", manufacturer]  # fmt: skip
    # A session of its own, as a terminal's foreground job: SIGINT is not ignored.
    server = subprocess.Popen(
        command, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True,
    )  # fmt: skip
    try:
        assert server.stdout is not None
        first = server.stdout.readline()
        assert first.startswith(f"serving 2 VDA 5050 2.1.0 vehicle(s) on {broker_url}:"), first
        assert "amr_0 as amr_0, amr_1 as amr_1" in first
        for serial in ("amr_0", "amr_1"):
            sniffer.wait_for(
                "connection", lambda b: b["connectionState"] == "ONLINE", "ONLINE", serial=serial
            )
        server.send_signal(signum)
        rest, _ = server.communicate(timeout=TIMEOUT * 2)
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()
    assert server.returncode == 0, rest
    assert "stopped at sim time" in rest and "Traceback" not in rest
    for serial in ("amr_0", "amr_1"):
        sniffer.wait_for(
            "connection", lambda b: b["connectionState"] == "OFFLINE", "OFFLINE", serial=serial
        )


def test_serve_refuses_a_bad_serve_section(tmp_path: Path) -> None:
    (tmp_path / "scenarios").mkdir()
    scenario = tmp_path / "scenarios" / "bad.yaml"
    scenario.write_text(SCENARIO.read_text().replace("state_period: 10", "state_period: 45"))
    (tmp_path / "served_fleet_master.py").symlink_to(REPO / "examples" / "served_fleet_master.py")
    result = subprocess.run(
        [sys.executable, "-m", "fleet_async", "serve", str(scenario), "--duration", "1"],
        capture_output=True, text=True, timeout=TIMEOUT * 4, check=False,
    )  # fmt: skip
    assert result.returncode == 2
    assert f"{scenario}: serve: Vda5050Config.state_period" in result.stderr
    assert "45" in result.stderr
