from __future__ import annotations

import logging

from fleet_async import DataMonitor
from fleet_async.core.view.monitor import SimulationMonitor


def test_headless_monitor_writes_figures_to_the_log(monkeypatch, caplog):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monitor = DataMonitor(title="Fleet", enable_gui=True)
    assert DataMonitor.window_possible() is False
    with caplog.at_level(logging.INFO, logger="fleet_async.core.view.monitor"):
        monitor.start()
        assert monitor.uses_window is False
        monitor.write_data({"sim_time": 1.5, "objects": 3})
        monitor.stop()
    assert "Fleet: sim_time=1.500, objects=3" in caplog.text


def test_monitor_gui_disabled_never_opens_a_window(monkeypatch):
    monkeypatch.setenv("DISPLAY", ":99")
    monitor = DataMonitor(enable_gui=False)
    monitor.start()
    assert monitor.uses_window is False
    monitor.stop()


def test_simulation_monitor_rate_limits_and_computes_rtf(monkeypatch):
    written = []

    class Sink:
        def write_data(self, data):
            written.append(data)

    times = iter([0.0, 0.5, 1.0, 2.5])
    monkeypatch.setattr("fleet_async.core.view.monitor.time.perf_counter", lambda: next(times))
    mon = SimulationMonitor(Sink(), period_s=1.0)  # type: ignore[arg-type]
    assert mon.update(0.0, 0, 5, 2, 0) is True
    assert mon.update(5.0, 50, 5, 2, 0) is False  # half a second later: not yet
    assert mon.update(10.0, 100, 5, 2, 1) is True
    assert written[-1]["real_time_factor"] == 10.0
    assert mon.update(25.0, 250, 5, 2, 1) is True
    assert written[-1] == {
        "sim_time": 25.0,
        "real_time_factor": 10.0,
        "steps": 250,
        "objects": 5,
        "agents": 2,
        "collisions": 1,
    }
