"""A scene description (plain data: tables, lists, strings, numbers, booleans) written as a TOML scene file, the
inverse of :func:`tomllib.loads` on what :mod:`ffrf.scenes.scene_file` reads: ``tomllib.loads(scene_toml(d)) == d``.

Top-level tables become ``[table]`` sections, top-level lists of tables ``[[table]]`` blocks (``[[bodies]]``,
``[[joints]]``), and everything below them inline tables and arrays, one body or joint per block. Floats are written
with :func:`repr`, the shortest text that reads back to the same float.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from numbers import Integral, Real
from typing import Any

from ffrf.errors import SceneError

__all__ = ["scene_toml"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    # JSON's escapes are TOML's basic-string escapes; DEL is a control character TOML wants escaped too.
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(value: Any, where: str) -> str:
    """One TOML value: a scalar, an array or an inline table."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        number = float(value)
        return repr(number) if math.isfinite(number) else ("nan" if math.isnan(number) else f"{number:+}")
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {_value(v, f'{where}.{k}')}" for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v, f"{where}[{k}]") for k, v in enumerate(value)) + "]"
    raise SceneError(f"{where}: a {type(value).__name__} has no TOML form; give tables, lists, strings and numbers")


def _section(entries: Mapping[str, Any], where: str) -> list[str]:
    return [f"{_key(k)} = {_value(v, f'{where}.{k}')}" for k, v in entries.items()]


def scene_toml(description: Mapping[str, Any]) -> str:
    """``description`` as TOML text (module docstring)."""

    def is_tables(value: Any) -> bool:
        return isinstance(value, list | tuple) and bool(value) and all(isinstance(v, Mapping) for v in value)

    plain = {k: v for k, v in description.items() if not isinstance(v, Mapping) and not is_tables(v)}
    lines = _section(plain, "scene file")
    for key, value in description.items():
        if isinstance(value, Mapping):
            lines += ["", f"[{_key(key)}]", *_section(value, key)]
        elif is_tables(value):
            for k, table in enumerate(value):
                lines += ["", f"[[{_key(key)}]]", *_section(table, f"{key}[{k}]")]
    return "\n".join(lines).lstrip("\n") + "\n"
