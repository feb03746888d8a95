"""The checkpoint's data codec: a state tree as JSON text plus numeric arrays, nothing callable.

A checkpoint holds plain data only, so that reading one cannot run code (a pickle can: its
``__reduce__`` calls any function it names). :func:`encode` turns the state tree into a
JSON-compatible document and a list of numeric numpy arrays; :func:`decode` turns them back.
What the tree may hold:

- ``None``, bools, ints, floats (NaN and infinities too), strings; lists, tuples, dicts (any
  key the codec takes), sets and deques; numpy arrays and scalars of bool, integer, float or
  complex dtype (never ``object``);
- the simulation and its objects, by reference (``{"sim": 0}``, ``{"obj": id}``), resolved
  against the simulation restored into; its random streams (``sim.rng_for``) by key;
- other numpy generators, as their bit generator's state (PCG64, Philox, SFC64, MT19937);
- members of enums and instances of classes defined in ``fleet_async.core`` (actions, poses,
  paths, controller parameters) and their methods (by name), rebuilt with ``object.__new__``
  and their attributes set, never through a constructor or ``__setstate__`` named by the file.
  An instance that appears twice (an action both running and timed) is written once and
  referred to (``{"ref": n}``).

Anything else (a function, a lambda, a bound method, an instance of a user's class, a lock) is
refused with the path to it, so ``save_state`` can name the plugin or controller that holds it.
"""

from __future__ import annotations

import collections
import enum
import importlib
import sys
import types
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["CodecError", "Resolver", "decode", "encode"]

_SCALARS = (type(None), bool, int, float, str)
_ARRAY_KINDS = "biufc"
_BIT_GENERATORS = {
    "PCG64": np.random.PCG64,
    "PCG64DXSM": np.random.PCG64DXSM,
    "Philox": np.random.Philox,
    "SFC64": np.random.SFC64,
    "MT19937": np.random.MT19937,
}
_PACKAGE = "fleet_async.core."  # the simulator's own value types; never interfaces, CLI, ...


class CodecError(ValueError):
    """A value the codec does not take; ``path`` says where it is in the state tree."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(f"{path}: {message}")
        self.path = path


class Resolver:
    """How references leave and re-enter the tree (the simulation's side).

    Args:
        ref_of: ``value -> tag dict`` for a value saved by reference (the simulation, its
            objects, its random streams), or None for any other value.
        resolve: ``tag dict -> value`` on the way back; raises ``ValueError`` for an
            unknown reference.
    """

    def __init__(
        self,
        ref_of: Callable[[Any], dict[str, Any] | None],
        resolve: Callable[[dict[str, Any]], Any],
    ) -> None:
        self.ref_of = ref_of
        self.resolve = resolve


def _class_name(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _own_class(name: object, path: str) -> type:
    """The ``fleet_async`` class ``module:QualName`` names (the only classes a file may name)."""
    if not isinstance(name, str) or ":" not in name:
        raise CodecError(path, f"expected a class name 'module:Name', got {name!r}")
    module_name, qualname = name.split(":", 1)
    if not module_name.startswith(_PACKAGE):
        raise CodecError(path, f"class {name!r} is not one of fleet_async's own")
    module = sys.modules.get(module_name)
    if module is None:
        try:  # fleet_async's modules have no side effects at import
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise CodecError(path, f"no module {module_name!r} ({exc})") from exc
    found: Any = module
    for part in qualname.split("."):
        found = getattr(found, part, None)
    if not isinstance(found, type) or found.__module__ != module_name:
        raise CodecError(path, f"{name!r} is not a class of fleet_async")
    return found


def _attributes(obj: Any) -> dict[str, Any]:
    if type(obj).__getstate__ is not getattr(object, "__getstate__", None):  # an action: no hook
        state = obj.__getstate__()
        if not isinstance(state, dict):
            raise TypeError(f"{type(obj).__name__}.__getstate__ must return a dict")
        return dict(state)
    attrs = dict(vars(obj)) if hasattr(obj, "__dict__") else {}
    for cls in type(obj).__mro__:
        for slot in getattr(cls, "__slots__", ()):
            if slot not in ("__dict__", "__weakref__") and hasattr(obj, slot):
                attrs[slot] = getattr(obj, slot)
    return attrs


class _Encoder:
    def __init__(self, resolver: Resolver) -> None:
        self.resolver = resolver
        self.arrays: list[np.ndarray] = []
        self.memo: dict[int, int] = {}
        self.keep: list[object] = []  # memo keys stay valid while encoding

    def value(self, obj: Any, path: str) -> Any:
        if type(obj) in _SCALARS:
            return {"f": repr(obj)} if type(obj) is float else obj
        ref = self.resolver.ref_of(obj)
        if ref is not None:
            return ref
        if isinstance(obj, np.ndarray):
            if obj.dtype.kind not in _ARRAY_KINDS:
                raise CodecError(path, f"array of dtype {obj.dtype} (only numeric arrays)")
            self.arrays.append(np.ascontiguousarray(obj))
            return {"array": len(self.arrays) - 1}
        if isinstance(obj, np.generic):
            if obj.dtype.kind not in _ARRAY_KINDS:
                raise CodecError(path, f"numpy scalar of dtype {obj.dtype}")
            return {"np": [obj.dtype.str, self.value(obj.item(), path)]}
        if isinstance(obj, np.random.Generator):
            bit = obj.bit_generator
            return {"rng": [type(bit).__name__, self.value(bit.state, f"{path}.state")]}
        if type(obj) in (list, tuple, set, frozenset, collections.deque):
            items = sorted(obj, key=repr) if isinstance(obj, (set, frozenset)) else obj
            tags: dict[type, str] = {list: "list", tuple: "tuple", set: "set", frozenset: "set"}
            tag = tags.get(type(obj), "deque")
            return {tag: [self.value(v, f"{path}[{i}]") for i, v in enumerate(items)]}
        if type(obj) is dict:
            return {
                "dict": [
                    [self.value(k, f"{path} key"), self.value(v, f"{path}[{k!r}]")]
                    for k, v in obj.items()
                ]
            }
        if isinstance(obj, types.MethodType) and not isinstance(obj.__self__, type):
            return self.method(obj, path)
        if isinstance(obj, enum.Enum) and type(obj).__module__.startswith(_PACKAGE):
            return {"enum": [_class_name(type(obj)), self.value(obj.value, path)]}
        return self.instance(obj, path)

    def method(self, method: types.MethodType, path: str) -> Any:
        """A method of a fleet_async object (a pick's stages name the action's own steps)."""
        name = method.__func__.__name__
        if getattr(type(method.__self__), name, None) is not method.__func__:
            raise CodecError(path, f"method {method.__qualname__} is not plain data")
        return {"method": [self.instance(method.__self__, f"{path}.__self__"), name]}

    def instance(self, obj: Any, path: str) -> Any:
        cls = type(obj)
        if not cls.__module__.startswith(_PACKAGE) or callable(obj) or isinstance(obj, type):
            what = getattr(obj, "__qualname__", None) or cls.__qualname__
            raise CodecError(
                path, f"{what} ({cls.__module__}.{cls.__qualname__}) is not plain data"
            )
        seen = self.memo.get(id(obj))
        if seen is not None:
            return {"ref": seen}
        self.memo[id(obj)] = len(self.memo)
        self.keep.append(obj)
        try:
            attrs = _attributes(obj)
        except TypeError as exc:
            raise CodecError(path, str(exc)) from exc
        fields = {k: self.value(v, f"{path}.{k}") for k, v in attrs.items()}
        return {"obj_of": [self.memo[id(obj)], _class_name(cls), fields]}


def encode(tree: Any, resolver: Resolver, root: str = "state") -> tuple[Any, list[np.ndarray]]:
    """``tree`` (called ``root`` in errors) as a JSON-compatible document and its arrays.

    Raises:
        CodecError: for a value that is not plain data, naming where it is.
    """
    encoder = _Encoder(resolver)
    return encoder.value(tree, root), encoder.arrays


class _Decoder:
    def __init__(self, arrays: list[np.ndarray], resolver: Resolver) -> None:
        self.arrays = arrays
        self.resolver = resolver
        self.memo: dict[int, Any] = {}

    def value(self, doc: Any, path: str, depth: int = 0) -> Any:
        if depth > 200:
            raise CodecError(path, "nested too deep")
        if doc is None or isinstance(doc, (bool, int, str)):
            return doc
        if not isinstance(doc, dict) or len(doc) != 1:
            raise CodecError(path, f"unexpected {type(doc).__name__} in the document")
        ((tag, body),) = doc.items()
        d = depth + 1
        if tag == "f" and isinstance(body, str):
            try:
                return float(body)
            except ValueError as exc:
                raise CodecError(path, f"bad float {body!r}") from exc
        if tag in ("list", "tuple", "set", "deque") and isinstance(body, list):
            items = [self.value(v, f"{path}[{i}]", d) for i, v in enumerate(body)]
            kind = {"list": list, "tuple": tuple, "set": set, "deque": collections.deque}[tag]
            return kind(items)
        if tag == "dict" and isinstance(body, list):
            out: dict[Any, Any] = {}
            for i, pair in enumerate(body):
                if not isinstance(pair, list) or len(pair) != 2:
                    raise CodecError(f"{path}[{i}]", "a dict entry is not a [key, value] pair")
                key = self.value(pair[0], f"{path} key", d)
                try:
                    out[key] = self.value(pair[1], f"{path}[{key!r}]", d)
                except TypeError as exc:
                    raise CodecError(path, f"unhashable key {key!r}") from exc
            return out
        if tag == "array" and isinstance(body, int) and 0 <= body < len(self.arrays):
            return self.arrays[body]
        if tag == "np" and isinstance(body, list) and len(body) == 2:
            return self.scalar(body, path, d)
        if tag == "rng" and isinstance(body, list) and len(body) == 2:
            return self.generator(body, path, d)
        if tag == "enum" and isinstance(body, list) and len(body) == 2:
            cls = _own_class(body[0], path)
            if not issubclass(cls, enum.Enum):
                raise CodecError(path, f"{body[0]!r} is not an enum")
            try:
                return cls(self.value(body[1], path, d))
            except ValueError as exc:
                raise CodecError(path, str(exc)) from exc
        if tag == "ref" and isinstance(body, int) and body in self.memo:
            return self.memo[body]
        if tag == "method" and isinstance(body, list) and len(body) == 2:
            return self.method(body, path, d)
        if tag == "obj_of" and isinstance(body, list) and len(body) == 3:
            return self.instance(body, path, d)
        try:
            return self.resolver.resolve(doc)
        except ValueError as exc:
            raise CodecError(path, str(exc)) from exc

    def scalar(self, body: list[Any], path: str, depth: int) -> Any:
        try:
            dtype = np.dtype(body[0])
        except TypeError as exc:
            raise CodecError(path, f"bad dtype {body[0]!r}") from exc
        if dtype.kind not in _ARRAY_KINDS:
            raise CodecError(path, f"numpy scalar of dtype {dtype}")
        return dtype.type(self.value(body[1], path, depth))

    def generator(self, body: list[Any], path: str, depth: int) -> np.random.Generator:
        kind = _BIT_GENERATORS.get(body[0]) if isinstance(body[0], str) else None
        if kind is None:
            raise CodecError(path, f"unknown bit generator {body[0]!r}")
        bit = kind()
        try:
            bit.state = self.value(body[1], path, depth)
        except (TypeError, ValueError, KeyError) as exc:
            raise CodecError(path, f"bad {body[0]} state ({exc})") from exc
        return np.random.Generator(bit)

    def method(self, body: list[Any], path: str, depth: int) -> Any:
        owner, name = self.value(body[0], path, depth), body[1]
        function = getattr(type(owner), name, None) if isinstance(name, str) else None
        if not isinstance(function, types.FunctionType) or name.startswith("__"):
            raise CodecError(path, f"{name!r} is not a method of {type(owner).__qualname__}")
        return getattr(owner, name)

    def instance(self, body: list[Any], path: str, depth: int) -> Any:
        memo_id, name, fields = body
        if not isinstance(memo_id, int) or memo_id in self.memo or not isinstance(fields, dict):
            raise CodecError(path, "malformed instance")
        cls = _own_class(name, path)
        if issubclass(cls, enum.Enum) or issubclass(cls, BaseException):
            raise CodecError(path, f"{name!r} cannot be rebuilt as an instance")
        obj = object.__new__(cls)
        self.memo[memo_id] = obj
        for key, value in fields.items():
            object.__setattr__(obj, key, self.value(value, f"{path}.{key}", depth))
        return obj


def decode(doc: Any, arrays: list[np.ndarray], resolver: Resolver) -> Any:
    """The state tree :func:`encode` turned into ``doc`` and ``arrays``.

    Raises:
        CodecError: for anything :func:`encode` does not write, naming where it is.
    """
    return _Decoder(arrays, resolver).value(doc, "state")
