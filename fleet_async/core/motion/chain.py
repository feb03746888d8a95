"""Building an agent's controller chain from its ``controller`` argument.

The chain is one base controller (index 0) and any number of high-level controllers; the
argument may be None, a registry name, a mapping, a list of mappings, a ControllerParams or a
Controller (see ``Agent``). Chains built from the same plain spec are the same, so a fleet
spawned one agent at a time parses and validates its spec once (a small cache keyed by the
spec's values).
"""

from __future__ import annotations

import logging
from typing import Any

from fleet_async.core.base.types import MotionMode, MovementDirection
from fleet_async.core.motion.controllers import (
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    OmniController,
    controller_class,
    create_controller,
    params_dict,
)

__all__ = ["build_controller_chain"]

logger = logging.getLogger(__name__)

# Only chains that are one built-in base controller are kept; each agent gets its own
# controller and its own copy of the params.
_CHAIN_CACHE: dict[tuple[Any, ...], tuple[type[KinematicController], ControllerParams, float]] = {}
_CHAIN_CACHE_SIZE = 256
_PLAIN = frozenset({str, int, float, bool, type(None), MotionMode, MovementDirection})


def _plain_items(mapping: dict[str, Any] | None) -> tuple[tuple[str, type, Any], ...] | None:
    """The mapping's items with each value's type (True == 1 == 1.0 as keys, but only 1.0 is
    a valid limit) when every value is a plain scalar, else None."""
    if not mapping:
        return ()
    for value in mapping.values():
        if type(value) not in _PLAIN:
            return None
    return tuple((key, type(value), value) for key, value in mapping.items())


def _chain_key(
    spec: Any, motion_mode: MotionMode, defaults: dict[str, Any] | None
) -> tuple[Any, ...] | None:
    base = _plain_items(defaults)
    if base is None:
        return None
    if spec is None or type(spec) is str:
        return (motion_mode, base, spec)
    if type(spec) is dict:
        items = _plain_items(spec)
        return None if items is None else (motion_mode, base, "dict", items)
    return None


def _copy_params(params: ControllerParams) -> ControllerParams:
    """An independent copy of validated params (no re-validation)."""
    twin = object.__new__(ControllerParams)
    twin.__dict__.update(params.__dict__)
    return twin


def build_controller_chain(
    spec: Any, motion_mode: MotionMode, defaults: dict[str, Any] | None = None
) -> list[Controller]:
    """Turn an Agent's ``controller`` argument into a chain (base first).

    Args:
        spec: None, a registry name, a mapping, a list of mappings, a ControllerParams or a
            Controller (see ``Agent``).
        motion_mode: Picks the base class when ``spec`` names none.
        defaults: Fleet-wide ControllerParams fields applied under the agent's own.
    """
    key = _chain_key(spec, motion_mode, defaults)
    if key is not None:
        hit = _CHAIN_CACHE.get(key)
        if hit is not None:
            return [_from_cache(hit)]
    chain = _build_chain(spec, motion_mode, defaults)
    if key is not None and len(chain) == 1:
        _remember(key, chain[0], motion_mode)
    return chain


def _from_cache(hit: tuple[type[KinematicController], ControllerParams, float]) -> Controller:
    cls, params, separation = hit
    if cls is DifferentialController:
        return DifferentialController(_copy_params(params), wheel_separation=separation)
    return cls(_copy_params(params))


def _remember(key: tuple[Any, ...], base: Controller, motion_mode: MotionMode) -> None:
    """Cache a built-in base built from a plain spec (not a mismatch that warns each time)."""
    kind: type[KinematicController] | None = (
        OmniController
        if type(base) is OmniController
        else DifferentialController
        if type(base) is DifferentialController and motion_mode is not MotionMode.OMNIDIRECTIONAL
        else None
    )
    if kind is None:
        return
    if len(_CHAIN_CACHE) >= _CHAIN_CACHE_SIZE:
        _CHAIN_CACHE.clear()
    separation = float(getattr(base, "wheel_separation", 0.0))
    _CHAIN_CACHE[key] = (kind, _copy_params(base.params), separation)


def _base_entry(entry: dict[str, Any], motion_mode: MotionMode, where: str) -> Controller:
    """The base controller of one mapping of a list spec (cached like a whole plain spec)."""
    items = _plain_items(entry)
    key = None if items is None else (motion_mode, "entry", items)
    if key is not None:
        hit = _CHAIN_CACHE.get(key)
        if hit is not None:
            return _from_cache(hit)
    ctrl = create_controller(entry, where=where)
    if key is not None:
        _remember(key, ctrl, motion_mode)
    return ctrl


def _build_chain(
    spec: Any, motion_mode: MotionMode, defaults: dict[str, Any] | None
) -> list[Controller]:
    base_cls: type[KinematicController] = (
        DifferentialController if motion_mode is MotionMode.DIFFERENTIAL else OmniController
    )
    defaults = dict(defaults or {})
    if spec is None:
        return [base_cls(ControllerParams(**defaults))]
    if isinstance(spec, ControllerParams):
        return [base_cls(ControllerParams(**{**defaults, **params_dict(spec)}))]
    if isinstance(spec, Controller):
        return [spec] if spec.is_base else [base_cls(ControllerParams(**defaults)), spec]
    entries = spec if isinstance(spec, list) else [spec]
    chain: list[Controller] = []
    base: Controller | None = None
    for i, entry in enumerate(entries):
        where = f"controller[{i}]" if isinstance(spec, list) else "controller"
        if isinstance(entry, dict) and "type" not in entry and "class" not in entry:
            entry = {"type": base_cls.motion_mode.value, **entry}  # params only: default base
        ctrl: Any = entry
        if isinstance(entry, dict) and _is_base_entry(entry, where):
            ctrl = _base_entry({**defaults, **entry}, motion_mode, where)
        elif isinstance(entry, (str, dict)):
            ctrl = create_controller(entry, where=where)
        if not isinstance(ctrl, Controller):
            raise ValueError(f"{where}: expected a name, mapping or Controller, got {entry!r}")
        if ctrl.is_base:
            if base is not None:
                raise ValueError(
                    f"{where}: a second base controller ({type(ctrl).__name__}); a chain has one "
                    f"base (already {type(base).__name__}) plus high-level controllers"
                )
            # motion_mode defaults to DIFFERENTIAL, so only an explicit OMNIDIRECTIONAL that a
            # differential controller contradicts is worth a warning.
            if (
                isinstance(ctrl, KinematicController)
                and motion_mode is MotionMode.OMNIDIRECTIONAL
                and ctrl.motion_mode is not motion_mode
            ):
                logger.warning(
                    "%s: controller type %s overrides motion_mode=%s",
                    where,
                    type(ctrl).__name__,
                    motion_mode.value,
                )
            base = ctrl
        else:
            chain.append(ctrl)
    if base is None:
        base = base_cls(ControllerParams(**defaults))
    return [base, *chain]


def _is_base_entry(entry: dict[str, Any], where: str) -> bool:
    return issubclass(controller_class(entry, where), KinematicController)
