"""Loading YAML configuration and mapping it onto parameter dataclasses.

Every error names what went wrong and where: the file (and line and column for YAML syntax), the
key, the bad value and what was expected. An unknown key is an error that suggests the nearest
valid key, never a silent ignore.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import enum
import importlib
import inspect
import os
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import yaml

from fleet_async.core.base.reprs import short_repr
from fleet_async.core.base.types import coerce_enum
from fleet_async.core.base.yaml_scalars import ScalarRuleLoader

__all__ = [
    "dataclass_from_dict",
    "forward_spawn_params",
    "load_config",
    "load_yaml_config",
    "merge_configs",
    "register_class",
    "resolve_class",
]

T = TypeVar("T")
PathLike = str | os.PathLike[str]

# Value types YAML produces. A value of one of these types that does not fit a field's annotation
# is a certain mismatch; any other object (a Pose, a numpy array, a pathlib.Path) is passed on
# unchecked for the dataclass's own __post_init__ to convert or reject.
_YAML_TYPES = (type(None), bool, int, float, str, list, tuple, dict)
_SCALARS = {bool: (bool,), int: (int,), float: (int, float), str: (str,)}


def load_yaml_config(config_path: PathLike, *, allow_empty: bool = True) -> dict[str, Any]:
    """Load a YAML file whose top level is a mapping.

    Args:
        config_path: Path of the YAML file.
        allow_empty: Whether an empty file (or one of comments only) is ``{}``; scenario
            loaders pass False, since an empty scenario is a mistake (a wrong or truncated file).

    Returns:
        The parsed mapping; ``{}`` for an empty file when ``allow_empty``.

    Raises:
        FileNotFoundError: If ``config_path`` is not a file (the message gives the absolute path).
        ValueError: If the YAML is malformed (naming the file, line and column), its top level
            is not a mapping (naming the file), or it is empty and ``allow_empty`` is False.
    """
    path = Path(config_path)
    if not path.is_file():
        raise FileNotFoundError(f"Config file not found: {path} (looked for {path.resolve()})")
    try:
        with path.open(encoding="utf-8") as stream:
            data = yaml.load(stream, Loader=ScalarRuleLoader)  # data only, one scalar rule
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        where = f"{path}, line {mark.line + 1}, column {mark.column + 1}" if mark else str(path)
        raise ValueError(f"{where}: invalid YAML: {problem}") from exc
    if data is None and not allow_empty:
        raise ValueError(
            f"{path}: the file is empty (no YAML mapping); a scenario needs at least one "
            "section, e.g. 'simulation:' or 'entities:'"
        )
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: top level must be a mapping, got {type(data).__name__}")
    return data


def merge_configs(
    base_config: Mapping[str, Any], override_config: Mapping[str, Any]
) -> dict[str, Any]:
    """Recursively merge two config mappings into a new dict, modifying neither.

    Mappings under the same key are merged; otherwise the override's value wins, including lists
    (replaced, not concatenated) and ``None``. The result shares no mutable values with the
    inputs.

    Args:
        base_config: Defaults.
        override_config: Values taking precedence.
    """
    merged = copy.deepcopy(dict(base_config))
    for key, value in override_config.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = merge_configs(merged[key], value)
        else:
            merged[key] = copy.deepcopy(value)
    return merged


def load_config(config_paths: PathLike | Sequence[PathLike]) -> dict[str, Any]:
    """Load YAML files with :func:`load_yaml_config` and merge them, later ones winning.

    Args:
        config_paths: A path, or a list of paths (``[]`` gives ``{}``).

    Raises:
        FileNotFoundError, ValueError: As :func:`load_yaml_config`, for the first bad file.
    """
    paths = [config_paths] if isinstance(config_paths, (str, os.PathLike)) else config_paths
    merged: dict[str, Any] = {}
    for path in paths:
        merged = merge_configs(merged, load_yaml_config(path))
    return merged


def resolve_class(dotted_path: str) -> Any:
    """Import and return a class (or any attribute) named by a dotted path.

    Args:
        dotted_path: ``"package.module.ClassName"``.

    Returns:
        The object named by the last component.

    Raises:
        ValueError: If ``dotted_path`` is not a ``module.Name`` string.
        ModuleNotFoundError: If the module cannot be imported.
        AttributeError: If the module has no such attribute.
    """
    parts = dotted_path.split(".") if isinstance(dotted_path, str) else []
    if len(parts) < 2 or not all(parts):
        raise ValueError(f"Expected a dotted path 'module.ClassName', got {dotted_path!r}")
    module_name, _, attr = dotted_path.rpartition(".")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        msg = f"Cannot resolve {dotted_path!r}: no module named {exc.name!r}"
        raise ModuleNotFoundError(msg, name=exc.name) from exc
    try:
        return getattr(module, attr)
    except AttributeError as exc:
        msg = f"Cannot resolve {dotted_path!r}: module {module_name!r} has no attribute {attr!r}"
        raise AttributeError(msg) from exc


def register_class(
    registry: dict[str, Any], name: str, cls: type | str, base: type, what: str
) -> None:
    """Put ``cls`` (a subclass of ``base``, or its dotted path) into ``registry`` under ``name``.

    Raises:
        ValueError: for an empty name.
        TypeError: if ``cls`` is not a subclass of ``base``.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"{what}: expected a non-empty name, got {name!r}")
    resolved = resolve_class(cls) if isinstance(cls, str) else cls
    if not (isinstance(resolved, type) and issubclass(resolved, base)):
        raise TypeError(f"{what}({name!r}): {cls!r} is not a {base.__name__} subclass")
    registry[name] = resolved


def dataclass_from_dict(
    cls: type[T],
    config: Mapping[str, Any],
    *,
    aliases: Mapping[str, str] | None = None,
    converters: Mapping[str, Callable[[Any], Any]] | None = None,
    strict_keys: Sequence[str] | None = None,
    source: PathLike | None = None,
    section: str | None = None,
    extra_keys: Sequence[str] = (),
) -> T:
    """Construct a dataclass from a config mapping by field introspection.

    Each ``init`` field is read from its config key (the field name, or its alias). Fields with
    defaults are optional. Values are checked against the (possibly string) annotations where a
    mismatch is certain: a ``str``, ``bool``, list or ``None`` for a number, a number for a
    ``str``, a scalar for a list, and so on; ints are accepted (as floats) for float fields.
    Strings for ``Enum`` fields are converted, matching member values case-insensitively or
    member names. Mappings for dataclass-typed fields are built recursively. Values of other
    types (e.g. a ``Pose``) are passed through for ``__post_init__`` to handle.

    Args:
        cls: The dataclass type.
        config: Config values, typically a YAML section.
        aliases: ``{field_name: config_key}``: read ``field_name`` from ``config_key``.
        converters: ``{field_name: callable}`` applied to the raw value instead of the checks
            above; a converter returning ``None`` leaves the field at its default.
        strict_keys: If given, only these fields are read; every other field keeps its default
            and other keys in ``config`` are ignored (not errors) in this mode.
        source: File the config came from, named in error messages.
        section: Name of the config section, used in messages instead of ``cls.__name__``.
        extra_keys: Keys the caller reads itself (e.g. ``pose`` and ``yaw``), named among the
            valid keys when an unknown key is reported.

    Returns:
        An instance of ``cls``.

    Raises:
        TypeError: If ``cls`` is not a dataclass.
        ValueError: For a non-mapping config, an unknown key (naming it, the nearest valid key
            and ``source``), a missing required field, a value of the wrong type or a bad enum
            string; also a ValueError from ``cls.__post_init__``, prefixed with ``source``.
    """
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise TypeError(f"dataclass_from_dict: expected a dataclass type, got {cls!r}")
    where = _where(source)
    label = section or cls.__name__
    if not isinstance(config, Mapping):
        raise ValueError(f"{where}{label}: expected a mapping, got {short_repr(config)}")
    aliases, converters = aliases or {}, converters or {}
    init_fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    selected = list(init_fields) if strict_keys is None else list(strict_keys)
    bad_names = [n for n in (*selected, *aliases, *converters) if n not in init_fields]
    if bad_names:
        raise ValueError(f"{label}: {bad_names[0]!r} is not a field of {cls.__name__}")
    key_of = {name: aliases.get(name, name) for name in selected}
    if strict_keys is None:
        known = set(key_of.values()) | set(key_of) | set(extra_keys)
        _reject_unknown_keys(config, known, where, label)
    hints = _type_hints(cls)
    kwargs: dict[str, Any] = {}
    for name, field in init_fields.items():
        key = key_of.get(name)
        if key is not None and key != name and key in config and name in config:
            raise ValueError(f"{where}{label}: give {key!r} or {name!r}, not both")
        if key is not None and key not in config:
            key = name if name in config else None
        if key is not None:
            hint, path = hints.get(name, Any), f"{label}.{key}"
            value = _convert(config[key], converters.get(name), hint, path, source)
            if value is not None or name not in converters:
                kwargs[name] = value
                continue
        if field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            key = key_of.get(name, name)
            of_field = "" if key == name else f" (field {name!r})"
            raise ValueError(f"{where}{label}: missing required key {key!r}{of_field}")
    try:
        return cls(**kwargs)
    except ValueError as exc:
        if not where or str(exc).startswith(where):
            raise
        raise ValueError(f"{where}{exc}") from exc


def forward_spawn_params(
    factory_method: Callable[..., Any],
    spawn_params: Any,
    *,
    aliases: Mapping[str, str] | None = None,
    extra_kwargs: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Build keyword arguments for a factory from the fields of a spawn-params dataclass.

    A field is forwarded when the factory has a parameter of that name (after ``aliases``), or
    always when the factory takes ``**kwargs``. Values are forwarded as-is (not copied).

    Args:
        factory_method: Target callable, e.g. ``Agent.from_urdf``.
        spawn_params: Dataclass instance holding the spawn parameters.
        aliases: ``{spawn_field: factory_param}`` renames, e.g. ``{"initial_pose": "pose"}``.
        extra_kwargs: Merged in last, overriding forwarded fields (e.g. ``{"sim_core": sim}``).

    Returns:
        A dict ready for ``factory_method(**result)``.

    Raises:
        TypeError: If ``spawn_params`` is not a dataclass instance.
        ValueError: If ``aliases`` names a field ``spawn_params`` does not have.
    """
    if not dataclasses.is_dataclass(spawn_params) or isinstance(spawn_params, type):
        raise TypeError(
            f"forward_spawn_params: expected a dataclass instance, got {spawn_params!r}"
        )
    aliases = aliases or {}
    field_names = [f.name for f in dataclasses.fields(spawn_params)]
    for name in aliases:
        if name not in field_names:
            raise ValueError(f"aliases: {name!r} is not a field of {type(spawn_params).__name__}")
    kinds = {p.name: p.kind for p in inspect.signature(factory_method).parameters.values()}
    takes_any = inspect.Parameter.VAR_KEYWORD in kinds.values()
    by_name = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    accepted = {name for name, kind in kinds.items() if kind in by_name}
    kwargs = {
        aliases.get(name, name): getattr(spawn_params, name)
        for name in field_names
        if takes_any or aliases.get(name, name) in accepted
    }
    kwargs.update(extra_kwargs or {})
    return kwargs


def _reject_unknown_keys(
    config: Mapping[Any, Any], known: set[str], where: str, label: str
) -> None:
    unknown = [key for key in config if key not in known]
    if not unknown:
        return
    parts = []
    for key in unknown:
        close = difflib.get_close_matches(str(key), sorted(known), n=1)
        parts.append(f"{key!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    noun = "key" if len(unknown) == 1 else "keys"
    valid = ", ".join(sorted(known))
    raise ValueError(f"{where}{label}: unknown {noun} {', '.join(parts)}; valid keys: {valid}")


def _type_hints(cls: type) -> dict[str, Any]:
    try:
        return typing.get_type_hints(cls)
    except (NameError, TypeError):
        # An annotation that cannot be resolved is left unchecked rather than guessed at.
        return {f.name: f.type for f in dataclasses.fields(cls) if not isinstance(f.type, str)}


def _convert(
    value: Any, converter: Callable[[Any], Any] | None, hint: Any, path: str, source: Any
) -> Any:
    if converter is None:
        return _check(value, hint, path, source)
    try:
        return converter(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{_where(source)}{path}: {exc}") from exc


def _where(source: PathLike | None) -> str:
    return f"{source}: " if source is not None else ""


def _check(value: Any, hint: Any, path: str, source: PathLike | None) -> Any:
    """Return ``value`` converted to fit ``hint``; raise ValueError on a certain mismatch."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        arms = [a for a in args if a is not type(None)]
        if value is None and len(arms) < len(args):
            return None
        if len(arms) == 1:  # Optional[X]: X's own message is the most specific
            return _check(value, arms[0], path, source)
        for arm in arms:
            try:
                return _check(value, arm, path, source)
            except ValueError:
                continue
        return _mismatch(value, hint, path, source)
    if origin is typing.Literal:
        return value if value in args else _mismatch(value, hint, path, source)
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        if isinstance(value, hint):
            return value
        try:
            return hint(value)
        except (TypeError, ValueError):
            return coerce_enum(hint, value, f"{_where(source)}{path}")
    if isinstance(hint, type) and dataclasses.is_dataclass(hint) and isinstance(value, Mapping):
        return dataclass_from_dict(hint, value, source=source, section=path)
    if not isinstance(value, _YAML_TYPES):
        return value
    return _check_yaml_value(value, hint, path, source)


def _check_yaml_value(value: Any, hint: Any, path: str, source: PathLike | None) -> Any:
    kind, args = typing.get_origin(hint) or hint, typing.get_args(hint)
    if kind in _SCALARS:
        fits = isinstance(value, _SCALARS[kind]) and isinstance(value, bool) is (kind is bool)
        if not fits:
            return _mismatch(value, hint, path, source)
        return float(value) if kind is float else value
    if kind in (list, tuple, Sequence):
        if not isinstance(value, (list, tuple)):
            return _mismatch(value, hint, path, source)
        variadic = kind is not tuple or (len(args) == 2 and args[1] is Ellipsis)
        item = args[0] if args and variadic else Any  # fixed-shape tuples: items unchecked
        items = [_check(v, item, f"{path}[{i}]", source) for i, v in enumerate(value)]
        return tuple(items) if kind is tuple else items
    if kind in (dict, Mapping):
        if not isinstance(value, dict):
            return _mismatch(value, hint, path, source)
        item = args[1] if len(args) == 2 else Any
        return {k: _check(v, item, f"{path}[{k!r}]", source) for k, v in value.items()}
    return value  # Any, object, other classes, typing constructs: not checkable with certainty


def _mismatch(value: Any, hint: Any, path: str, source: PathLike | None) -> Any:
    expected = _type_name(hint)
    note = ""
    if isinstance(value, str) and expected in ("float", "int"):
        try:
            float(value)
            note = " (YAML 1.1 reads 1e-3 as a string; write 1.0e-3)"
        except ValueError:
            pass
    got = f"{short_repr(value)} ({type(value).__name__})"
    raise ValueError(f"{_where(source)}{path}: expected {expected}, got {got}{note}")


def _type_name(hint: Any) -> str:
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return " | ".join(_type_name(arm) for arm in typing.get_args(hint))
    return hint.__name__ if isinstance(hint, type) else str(hint).replace("typing.", "")
