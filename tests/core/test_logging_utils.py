"""LazyLogger / NamedLazyLogger: lazy evaluation, prefixes, caller location."""

from __future__ import annotations

import inspect
import logging
import subprocess
import sys

import pytest

from fleet_async.core.base.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    lazy_log,
    wrap_existing_logger,
)

NAME = "fleet_async.test.lazy"


def _counting(text: str) -> tuple[list[int], object]:
    calls: list[int] = []

    def build() -> str:
        calls.append(1)
        return text

    return calls, build


def test_callable_is_not_evaluated_when_level_disabled(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger=NAME)
    log = LazyLogger(NAME)
    calls, build = _counting("expensive")

    log.debug(build)

    assert calls == []
    assert caplog.records == []


def test_callable_is_evaluated_once_when_level_enabled(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = LazyLogger(NAME)
    calls, build = _counting("expensive")

    log.debug(build)

    assert calls == [1]
    assert [r.getMessage() for r in caplog.records] == ["expensive"]
    assert caplog.records[0].levelno == logging.DEBUG


@pytest.mark.parametrize(
    ("method", "level"),
    [
        ("debug", logging.DEBUG),
        ("info", logging.INFO),
        ("warning", logging.WARNING),
        ("error", logging.ERROR),
        ("critical", logging.CRITICAL),
    ],
)
def test_each_level_method_logs_at_its_level(
    caplog: pytest.LogCaptureFixture, method: str, level: int
) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)

    getattr(LazyLogger(NAME), method)("plain %s", "text")

    assert [(r.levelno, r.getMessage()) for r in caplog.records] == [(level, "plain text")]


def test_record_points_at_the_callers_line(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = get_named_lazy_logger(NAME, "[p] ")

    log.info(lambda: "where am I")
    expected_line = inspect.currentframe().f_lineno - 1  # type: ignore[union-attr]

    record = caplog.records[0]
    assert record.funcName == "test_record_points_at_the_callers_line"
    assert record.lineno == expected_line
    assert record.pathname == __file__


def test_user_stacklevel_counts_from_the_wrapper_call(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = LazyLogger(NAME)

    def helper() -> None:
        log.warning("from helper", stacklevel=2)

    helper()

    assert caplog.records[0].funcName == "test_user_stacklevel_counts_from_the_wrapper_call"


def test_kwargs_are_forwarded(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = LazyLogger(NAME)
    try:
        raise RuntimeError("boom")
    except RuntimeError:
        log.error(lambda: "failed", exc_info=True, extra={"robot": "r1"})

    record = caplog.records[0]
    assert record.exc_info is not None
    assert record.exc_info[0] is RuntimeError
    assert record.robot == "r1"  # type: ignore[attr-defined]


def test_is_enabled_for_and_logger_property() -> None:
    std = logging.getLogger(NAME + ".levels")
    std.setLevel(logging.WARNING)
    try:
        log = wrap_existing_logger(std)
        assert log.logger is std
        assert log.isEnabledFor(logging.ERROR)
        assert not log.isEnabledFor(logging.INFO)
    finally:
        std.setLevel(logging.NOTSET)


def test_factories_and_defaults() -> None:
    assert get_lazy_logger(NAME).logger is logging.getLogger(NAME)
    assert LazyLogger().logger is logging.getLogger()
    explicit = logging.getLogger(NAME + ".explicit")
    assert LazyLogger("ignored", logger=explicit).logger is explicit
    named = get_named_lazy_logger(NAME, "[x] ")
    assert isinstance(named, NamedLazyLogger)
    assert named.prefix == "[x] "
    assert named.logger is logging.getLogger(NAME)


def test_named_logger_prefixes_and_updates(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = NamedLazyLogger(NAME, prefix="[obj:1] ")

    log.info("spawned")
    log.set_prefix("[Agent:1:robot_A] ")
    log.debug(lambda: "pos=[1.0, 2.0]")

    assert log.prefix == "[Agent:1:robot_A] "
    assert [r.getMessage() for r in caplog.records] == [
        "[obj:1] spawned",
        "[Agent:1:robot_A] pos=[1.0, 2.0]",
    ]


def test_named_logger_does_no_work_when_disabled(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger=NAME)
    log = NamedLazyLogger(NAME, prefix="[p] ")
    calls, build = _counting("x")

    log.info(build)

    assert calls == []
    assert caplog.records == []


def test_percent_in_prefix_does_not_break_args(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=NAME)
    log = NamedLazyLogger(NAME, prefix="[100%] ")

    log.info("moved %d m", 3)
    log.info("no args, literal %s")

    assert [r.getMessage() for r in caplog.records] == [
        "[100%] moved 3 m",
        "[100%] no args, literal %s",
    ]


def test_lazy_log_decorator_wraps_loggers() -> None:
    @lazy_log
    def make_logger(suffix: str) -> logging.Logger:
        """Docstring kept by functools.wraps."""
        return logging.getLogger(f"{NAME}.{suffix}")

    wrapped = make_logger("deco")

    assert isinstance(wrapped, LazyLogger)
    assert wrapped.logger is logging.getLogger(f"{NAME}.deco")
    assert make_logger.__name__ == "make_logger"
    assert make_logger.__doc__ == "Docstring kept by functools.wraps."


def test_lazy_log_passes_lazy_loggers_through() -> None:
    inner = LazyLogger(NAME)

    @lazy_log
    def already_lazy() -> LazyLogger:
        return inner

    assert already_lazy() is inner


def test_import_has_no_logging_side_effects() -> None:
    code = (
        "import logging, fleet_async.core.base.logging_utils as m\n"
        "root = logging.getLogger()\n"
        "assert root.handlers == [] and root.level == logging.WARNING, root\n"
        "assert logging.getLogger(m.__name__).handlers == []\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
