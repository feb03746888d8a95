"""Seed examples of pybullet_fleet.logging_utils (LazyLogger, NamedLazyLogger, helpers)."""

import logging

import numpy as np
from parity_trace import Trace
from pybullet_fleet.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    wrap_existing_logger,
)

T = Trace()
numpy_array = np.arange(3)
arr = numpy_array
evaluated = []


class Capture(logging.Handler):
    def __init__(self):
        super().__init__()
        self.lines = []

    def emit(self, record):
        self.lines.append(record.getMessage())


cap = Capture()
logging.getLogger().addHandler(cap)
logging.getLogger().setLevel(logging.INFO)
with T.probe("LazyLogger") as out:
    logger = LazyLogger(__name__)
    logger.debug(lambda: evaluated.append("debug") or f"Expensive array: {numpy_array}")
    logger.info(lambda: f"Array: {arr}")
    out["evaluated_debug"] = evaluated
    out["enabled_debug"] = logger.isEnabledFor(logging.DEBUG)
    out["logger_type"] = type(logger.logger).__name__
with T.probe("lazy_log_decorator") as out:
    try:
        from pybullet_fleet.logging_utils import lazy_log  # the seed's decorator example uses it

        @lazy_log
        def my_logger():
            return logging.getLogger(__name__)

        logger = my_logger()
        logger.debug(lambda: f"Array: {arr}")
        out["lazy_log"] = True
    except ImportError as exc:
        out["lazy_log"] = f"ImportError: {exc}"[:60]
with T.probe("NamedLazyLogger") as out:
    log = NamedLazyLogger(__name__)
    log.set_prefix(f"[obj:{3}] ")
    log.set_prefix(f"[Agent:{3}:{'robot_A'}] ")
    log.info("Path complete")
    log.debug(lambda: f"pos={[1.0, 2.0]}")
    out["prefix"] = log.prefix
with T.probe("helpers") as out:
    log = get_named_lazy_logger(__name__, f"[Agent:{7}] ")
    log.info(lambda: f"pos={[1, 2]}")
    logger = get_lazy_logger(__name__)
    logger.info(lambda: f"Expensive: {numpy_array}")
    standard_logger = logging.getLogger(__name__)
    lazy_logger = wrap_existing_logger(standard_logger)
    lazy_logger.info(lambda: f"Array: {arr}")
    out["ok"] = True
with T.probe("captured_lines") as out:
    out["lines"] = cap.lines
T.dump()
