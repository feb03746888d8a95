from __future__ import annotations

import logging

import pytest

from fleet_async import EventBus, SimEvents


def test_handlers_run_by_ascending_priority_then_registration_order():
    # As the reference API's bus: "Lower priority = executed first", equal priority FIFO.
    bus = EventBus()
    calls = []
    bus.on("e", lambda **kw: calls.append("low"), priority=-1)
    bus.on("e", lambda **kw: calls.append("first0"))
    bus.on("e", lambda **kw: calls.append("high"), priority=5)
    bus.on("e", lambda **kw: calls.append("second0"))
    assert bus.emit("e") == 4
    assert calls == ["low", "first0", "second0", "high"]


def test_a_handler_gets_only_the_payload_keys_it_names():
    bus = EventBus()
    seen = []
    bus.on("e", lambda other: seen.append(("named", other)))
    bus.on("e", lambda other, *, sim=None: seen.append(("kw-only", other, sim)))
    bus.on("e", lambda **kw: seen.append(("all", sorted(kw))))
    bus.emit("e", sim="S", obj_a=1, obj_b=2, other=2)
    assert seen == [("named", 2), ("kw-only", 2, "S"), ("all", ["obj_a", "obj_b", "other", "sim"])]
    bus.on("f", lambda missing: None)
    with pytest.raises(TypeError, match="missing"):
        bus.emit("f", other=1)


def test_on_change_reports_subscriptions():
    changes = []
    bus = EventBus(on_change=changes.append)

    def handler(**kw):
        pass

    bus.on("a", handler)
    bus.off("a", handler)
    bus.off("a", handler)  # not subscribed: no change
    bus.on("b", handler)
    bus.clear()
    assert changes == ["a", "a", "b", "b"]


def test_payload_is_passed_as_keywords():
    bus = EventBus()
    seen = {}
    bus.on("e", lambda **kw: seen.update(kw))
    bus.emit("e", a=1, b="x")
    assert seen == {"a": 1, "b": "x"}


def test_off_unsubscribes_and_reports():
    bus = EventBus()

    def handler(**kw):
        raise AssertionError("must not run")

    bus.on("e", handler)
    assert bus.off("e", handler) is True
    assert bus.off("e", handler) is False
    assert bus.emit("e") == 0
    assert not bus.has_handlers("e")


def test_subscribe_decorator_and_counts():
    bus = EventBus()

    @bus.subscribe("a", priority=2)
    def one(**kw):
        pass

    bus.on("b", one)
    assert bus.handler_count("a") == 1
    assert bus.handler_count() == 2
    bus.clear("a")
    assert bus.handler_count() == 1
    bus.clear()
    assert bus.handler_count() == 0


def test_handler_exception_propagates_by_default():
    bus = EventBus()

    def boom(**kw):
        raise RuntimeError("bad handler")

    bus.on("e", boom)
    with pytest.raises(RuntimeError, match="bad handler"):
        bus.emit("e")


def test_log_mode_logs_and_continues(caplog):
    bus = EventBus(on_error="log")
    calls = []

    def boom(**kw):
        raise RuntimeError("bad handler")

    bus.on("e", boom, priority=-1)
    bus.on("e", lambda **kw: calls.append(1))
    with caplog.at_level(logging.ERROR):
        bus.emit("e")
    assert calls == [1]
    assert "bad handler" in caplog.text


def test_handler_added_during_emit_runs_next_time_only():
    bus = EventBus()
    calls = []

    def first(**kw):
        calls.append("first")
        bus.on("e", lambda **kw: calls.append("late"))

    bus.on("e", first)
    bus.emit("e")
    assert calls == ["first"]


def test_bad_arguments_are_rejected():
    bus = EventBus()
    with pytest.raises(ValueError, match="non-empty string"):
        bus.on("", lambda **kw: None)
    with pytest.raises(TypeError, match="not callable"):
        bus.on("e", 3)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="on_error"):
        EventBus(on_error="ignore")


def test_sim_events_lists_every_name_once():
    names = SimEvents.all()
    assert len(names) == len(set(names)) == 22
    assert SimEvents.PRE_STEP in names and SimEvents.ACTION_FAILED in names
    assert SimEvents.TASK_COMPLETED in names and SimEvents.TASK_FAILED in names
    assert SimEvents.MISSION_FAILED in names
