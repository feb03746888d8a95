"""Whether the step's hot loops run as compiled kernels (numba) or as numpy passes.

The kinematic engine's advance (``motion/advance_jit.py``), the collision broad phase and the
safety fields' exact pair test (``collision/check_jit.py``) each have a numba kernel beside
their numpy code. The
kernels are an optional extra (``pip install "fleet-async[fast]"``: numba ships wheels for
Linux, macOS and Windows, no compiler needed); the numpy code is the reference and always
there. Both give the same results bit for bit (``tests/core/test_compiled.py`` runs both on
one seeded workload), so which one runs changes only the speed.

``SimulationParams.kernels`` picks: ``"numpy"`` (the default) never uses numba, ``"auto"`` uses
it when it imports, ``"numba"`` requires it and fails with an ``ImportError`` saying how to
install it. Kernels are compiled on their first call and cached on disk (``cache=True``), so
only the first run on a machine pays the compilation (about 7 s of CPU); every later process
still pays about a second on its first step to import numba and load the cached kernels, which
is why numpy stays the default (measured in docs/performance.md).
"""

from __future__ import annotations

import logging

__all__ = ["KERNEL_MODES", "use_numba"]

KERNEL_MODES = ("auto", "numpy", "numba")
"""The values of ``SimulationParams.kernels``."""

_log = logging.getLogger(__name__)
_available: bool | None = None  # numba imported (None: not tried yet)
_reason = ""


def _numba_imports() -> bool:
    """Import numba once per process; remember why it failed."""
    global _available, _reason
    if _available is None:
        try:
            import numba  # noqa: F401  (imported for its side effect: is it there)
        except Exception as exc:  # ImportError, or a numba that refuses this numpy
            _available, _reason = False, f"{type(exc).__name__}: {exc}"
            _log.debug("numba not used: %s", _reason)
        else:
            _available = True
    return _available


def use_numba(mode: str) -> bool:
    """Whether to run the compiled kernels under ``SimulationParams.kernels = mode``.

    Raises:
        ImportError: ``mode`` is ``"numba"`` and numba does not import (the message says why
            and how to install it).
        ValueError: ``mode`` is not one of :data:`KERNEL_MODES`.
    """
    if mode == "numpy":
        return False
    if mode not in KERNEL_MODES:
        raise ValueError(f"SimulationParams.kernels: expected one of {KERNEL_MODES}, got {mode!r}")
    if _numba_imports():
        return True
    if mode == "numba":
        raise ImportError(
            "SimulationParams.kernels='numba' asks for the compiled kernels, but numba does not "
            f'import ({_reason}); install the extra: pip install "fleet-async[fast]", or use '
            "kernels='auto' (numba when present) or 'numpy'"
        )
    return False
