"""One rule for what a plain YAML scalar means, in scenario files and in ``--set`` values.

PyYAML reads YAML 1.1, where ``no`` is false, ``1:30`` is 90 (base 60), ``0x1F`` is 31 and
``010`` is 8: surprises for someone who wrote a name, a time or a number. fleet_async reads
every unquoted scalar by this rule instead (YAML 1.2's core schema, minus its surprises):

- ``true`` / ``false`` (also ``True``, ``TRUE``, ...) are booleans; ``null``, ``~`` or nothing
  is null;
- a decimal integer (``42``, ``-3``) is an int; a decimal number with a point or an exponent
  (``0.5``, ``.5``, ``1e-3``, ``-2.5E+2``) or ``inf``, ``-inf``, ``nan`` (also ``.inf``, ``.nan``)
  is a float;
- forms YAML 1.1 reads otherwise than a reader expects are **refused**, naming the value and
  what to write instead: ``yes`` / ``no`` / ``on`` / ``off`` (also ``No``, ``OFF``, ...; write
  ``true`` or ``false``, or quote the text), base-60 numbers ``1:30``, ``0x1F``, ``0o17``,
  ``0b101``, ``010``, ``1_000`` and dates ``2024-01-31`` (write the number or the text you
  mean, quoted for text);
- anything else is a string. A quoted scalar (``"no"``, ``'1:30'``) is always a string.
"""

from __future__ import annotations

import re
from typing import Any

import yaml

__all__ = ["AMBIGUOUS", "ScalarRuleLoader", "load_yaml_text"]

_BOOL = re.compile(r"true|True|TRUE|false|False|FALSE")
_NULL = re.compile(r"null|Null|NULL|~|")
_INT = re.compile(r"[-+]?(0|[1-9][0-9]*)")
_FLOAT = re.compile(
    r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?"
    r"|[-+]?\.?(inf|Inf|INF)|\.?(nan|NaN|NAN)"
)
AMBIGUOUS = re.compile(
    r"yes|Yes|YES|no|No|NO|on|On|ON|off|Off|OFF"
    r"|[-+]?[0-9][0-9_]*(:[0-5]?[0-9])+(\.[0-9_]*)?"  # base 60
    r"|[-+]?0[xX][0-9a-fA-F_]+|[-+]?0[oO]?[0-7_]+|[-+]?0[bB][01_]+"
    r"|[-+]?[0-9]+(_[0-9]+)+(\.[0-9_]*)?"
    r"|[0-9]{4}-[0-9]{1,2}-[0-9]{1,2}([Tt ].*)?"
)
"""Plain scalars the rule refuses (see the module's docstring)."""

_AMBIGUOUS_TAG = "tag:fleet_async,2026:ambiguous"


def _explain(value: str) -> str:
    if value.lower() in ("yes", "no", "on", "off"):
        return "write true or false for a boolean, or quote it for text"
    return "write the number you mean in decimals, or quote it for text"


class ScalarRuleLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` with the scalar rule of this module (nothing but data is built)."""

    yaml_implicit_resolvers = {}  # noqa: RUF012 - PyYAML reads it here; ours, not SafeLoader's

    def construct_ambiguous(self, node: yaml.ScalarNode) -> Any:
        """Refuse a scalar YAML 1.1 reads otherwise than a reader expects.

        Raises:
            yaml.constructor.ConstructorError: naming the value and what to write instead.
        """
        value = str(node.value)
        raise yaml.constructor.ConstructorError(
            None,
            None,
            f"{value!r} is ambiguous (YAML 1.1 and 1.2 read it differently): {_explain(value)}",
            node.start_mark,
        )


for _tag, _pattern, _first in (  # the refused forms first: the first match wins
    (_AMBIGUOUS_TAG, AMBIGUOUS, "-+0123456789yYnNoO"),
    ("tag:yaml.org,2002:merge", re.compile("<<"), "<"),
    ("tag:yaml.org,2002:bool", _BOOL, "tTfF"),
    ("tag:yaml.org,2002:null", _NULL, ["~", "n", "N", ""]),
    ("tag:yaml.org,2002:int", _INT, "-+0123456789"),
    ("tag:yaml.org,2002:float", _FLOAT, "-+.0123456789iInN"),
):
    ScalarRuleLoader.add_implicit_resolver(
        _tag, re.compile(f"^(?:{_pattern.pattern})$"), list(_first)
    )
ScalarRuleLoader.add_constructor(_AMBIGUOUS_TAG, ScalarRuleLoader.construct_ambiguous)


def load_yaml_text(text: str) -> Any:
    """``text`` read as YAML by the scalar rule.

    Raises:
        yaml.YAMLError: for malformed YAML or a refused scalar (with its line and column).
    """
    return yaml.load(text, Loader=ScalarRuleLoader)  # a SafeLoader: data only
