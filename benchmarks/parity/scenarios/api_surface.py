"""Every name the seed documents, with its signature: present? same parameters as the seed?"""

# PARITY_NO_PLAIN_RENAME: this script parses the seed's pybullet_fleet.<module> headings.

import dataclasses
import enum
import importlib
import inspect
import os
import re

from parity_trace import Trace

T = Trace()
SEED = os.environ.get("PARITY_SEED")
OURS = os.environ.get("FLEET_PKG") == "fleet_async"
HEAD = re.compile(r"^- (?:class )?pybullet_fleet\.(\w+)\.(\w+)(?:\((.*)\))?(?::.*)?$")
METHOD = re.compile(r"^- (?:classmethod |abstractmethod |staticmethod )?([a-z_]\w*)\((.*)\)\s*$")
PROP = re.compile(r"^- property ([a-z_]\w*)(?::.*)?$")
ATTR = re.compile(r"^- ([a-z_]\w*)(?:: [^=]*)?(?: = .*)?$")
MEMBER = re.compile(r"^- ([A-Z][A-Z0-9_]*) = (.*)$")


def module(name):
    if OURS:  # the harness does not rewrite dynamic imports; go through the same lookup
        import parity_shim

        return parity_shim.module(name)
    return importlib.import_module(f"pybullet_fleet.{name}")


def split_args(text):
    depth, cur, out = 0, "", []
    for ch in text:
        depth += ch in "([{<"
        depth -= ch in ")]}>"
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    names = [a.split("=")[0].strip().lstrip("*") for a in out if a.strip() and a.strip() != "*"]
    return [n for n in names if n not in ("self", "cls")]


def compare(got, seed):
    """'exact', 'extends' (the seed's parameters first, in order, then more), or 'differs'."""
    if got is None:
        return None
    if got == seed:
        return "exact"
    return "extends" if got[: len(seed)] == seed else "differs"


def params_of(obj):
    if inspect.isclass(obj) and issubclass(obj, (enum.Enum, tuple)):
        return None  # enums and named tuples: their members are checked instead
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return None
    return [
        p
        for p in sig.parameters
        if p not in ("self", "cls")
        and sig.parameters[p].kind
        not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    ]


def entries(text):
    """(key, module, owner, member, kind, seed params) for each documented item."""
    cls = None
    for line in text.splitlines():
        line = line.strip()
        if line.endswith(" module") and line.startswith("pybullet_fleet."):
            cls = None
            continue
        m = HEAD.match(line)
        if m:
            mod, name, args = m.groups()
            is_class = line.startswith("- class ")
            cls = (mod, name) if is_class else None
            yield f"{mod}.{name}", mod, name, None, "class" if is_class else "function", args
            continue
        if cls is None:
            continue
        for regex, kind in (
            (METHOD, "method"),
            (PROP, "property"),
            (MEMBER, "member"),
            (ATTR, "attribute"),
        ):
            m = regex.match(line)
            if m:
                args = m.group(2) if kind in ("method", "member") else None
                yield f"{cls[0]}.{cls[1]}.{m.group(1)}", cls[0], cls[1], m.group(1), kind, args
                break


def check(mod, owner, member, kind, seed_args):
    try:
        obj = getattr(module(mod), owner)
    except Exception as exc:
        return {"exists": False, "why": type(exc).__name__}
    if member is None:
        if kind == "function" and seed_args is None:  # a module constant
            return {
                "exists": True,
                "value": obj if isinstance(obj, (int, float, str)) else type(obj).__name__,
            }
        got = params_of(obj)
        seed = split_args(seed_args or "")
        return {"exists": True, "params": got, "vs_seed": compare(got, seed)}
    if kind == "member":
        value = getattr(obj, member, None)
        return {"exists": value is not None, "value": getattr(value, "value", value)}
    static = inspect.getattr_static(obj, member, None)
    fields = {f.name for f in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) else set()
    if static is None and member not in fields:
        # May be an instance attribute set in __init__: look for it in the source.
        try:
            src = inspect.getsource(obj)
        except (OSError, TypeError):
            src = ""
        return {"exists": f"self.{member}" in src or None}
    if kind == "method":
        fn = getattr(obj, member)
        got = params_of(fn)
        seed = split_args(seed_args or "")
        return {"exists": True, "params": got, "vs_seed": compare(got, seed)}
    actual = (
        "property"
        if isinstance(static, property)
        else ("field" if member in fields else "attribute")
    )
    return {"exists": True, "kind": actual} if kind == "property" else {"exists": True}


if SEED and os.path.isfile(SEED):
    with open(SEED, encoding="utf-8") as fh:
        text = fh.read()
    for key, mod, owner, member, kind, args in entries(text):
        if key in T.data:
            continue
        T[key] = check(mod, owner, member, kind, args)
else:
    T["skipped"] = "seed text not found (set PARITY_SEED / --seed)"
T.dump()
