"""Keys of TOML tables: their kinds, required or not, checks of their values, and the walk that checks a table.

Plain data (one :class:`Key` per key), so that documentation, checks and error messages cannot drift apart; the
scene's own tables are in :mod:`ffrf.scenes.scene_schema`, a linkage file's in :mod:`ffrf.scenes.linkage_file`.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ffrf.errors import SceneError

__all__ = [
    "SHORTEST_DIRECTION",
    "Key",
    "at_least",
    "between",
    "check_table",
    "label",
    "non_negative",
    "nonzero",
    "nonzero_vector",
    "one_of",
    "ordered_pair",
    "positive",
    "unique",
    "unit_quaternion",
]


@dataclass(frozen=True)
class Key:
    """One key: its kind (``number``, ``integer``, ``string``, ``boolean``, ``vector3``, ``vector4``,
    ``pair``, ``numbers``, ``strings``, ``table`` or ``tables``), whether it is required, a check of its
    value returning the problem (or ``None``), and, for ``table``/``tables``, the keys inside."""

    kind: str
    required: bool = False
    check: Callable[[object], str | None] | None = None
    keys: Mapping[str, Key] | None = None


def positive(value) -> str | None:
    return None if value > 0 else f"must be > 0, got {value!r}"


def non_negative(value) -> str | None:
    return None if value >= 0 else f"must be >= 0, got {value!r}"


def between(low: float, high: float, closed: bool) -> Callable[[object], str | None]:
    def check(value) -> str | None:
        inside = low <= value <= high if closed else low < value < high
        bounds = f"[{low:g}, {high:g}]" if closed else f"({low:g}, {high:g})"
        return None if inside else f"must lie in {bounds}, got {value!r}"

    return check


def one_of(choices: tuple) -> Callable[[object], str | None]:
    return lambda value: None if value in choices else f"must be one of {list(choices)}, got {value!r}"


def at_least(bound: int) -> Callable[[Any], str | None]:
    return lambda value: None if value >= bound else f"must be >= {bound}, got {value!r}"


#: Shortest direction vector taken: shorter ones lose their digits when squared (1e-300 squares to 0).
SHORTEST_DIRECTION = 1e-9


def nonzero_vector(value) -> str | None:
    length = math.hypot(*value)
    if length == 0.0:
        return "has zero length; give a direction such as [0.0, 0.0, 1.0]"
    if length < SHORTEST_DIRECTION:
        return (
            f"has length {length:.3g}, too short to give a direction (below {SHORTEST_DIRECTION:g}); give a "
            "direction such as [0.0, 0.0, 1.0]"
        )
    return None


def ordered_pair(value) -> str | None:
    return None if value[0] <= value[1] else f"is reversed ({value!r}); give [t_min, t_max]"


def nonzero(value) -> str | None:
    return None if value != 0 else "must not be 0 (a drive that never turns); remove the drive or give a speed"


def unit_quaternion(value) -> str | None:
    norm = math.sqrt(sum(v * v for v in value))
    return (
        None if abs(norm - 1.0) < 1e-9 else f"must have unit length (Euler parameters e0, e1, e2, e3), norm {norm:.6g}"
    )


_KIND_NAMES = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "vector3": "a list of 3 numbers",
    "vector4": "a list of 4 numbers",
    "pair": "a list of 2 numbers",
    "table": "a table {...}",
    "tables": "a list of tables ([[...]] or [{...}, ...])",
    "strings": "a list of strings",
    "numbers": "a list of numbers",
}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _type_problem(kind: str, value) -> str | None:
    """Why ``value`` is not of ``kind`` (None if it is); nan and inf are not numbers of a scene."""
    if kind in ("number", "integer"):
        if not _is_number(value) or (kind == "integer" and not isinstance(value, int)):
            return f"must be {_KIND_NAMES[kind]}, got {value!r}"
        return None if math.isfinite(value) else f"must be finite, got {value!r}"
    if kind in ("vector3", "vector4", "pair"):
        size = {"vector3": 3, "vector4": 4, "pair": 2}[kind]
        if not isinstance(value, list) or len(value) != size or not all(_is_number(v) for v in value):
            return f"must be {_KIND_NAMES[kind]}, got {value!r}"
        return None if all(math.isfinite(v) for v in value) else f"must be finite, got {value!r}"
    if kind == "numbers":
        if not isinstance(value, list) or not value or not all(_is_number(v) for v in value):
            return f"must be {_KIND_NAMES[kind]} (at least one), got {value!r}"
        return None if all(math.isfinite(v) for v in value) else f"must be finite, got {value!r}"
    if kind == "strings":
        ok = isinstance(value, list) and value and all(isinstance(v, str) for v in value)
        return None if ok else f"must be {_KIND_NAMES[kind]} (at least one), got {value!r}"
    expected = {"string": str, "boolean": bool, "table": dict}.get(kind)
    if expected is not None:
        return None if isinstance(value, expected) else f"must be {_KIND_NAMES[kind]}, got {value!r}"
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        return f"must be {_KIND_NAMES[kind]}, got {value!r}"
    return None


def check_table(table: dict, keys: Mapping[str, Key], where: str) -> None:
    """Raise :class:`SceneError` for the first key of ``table`` (and of the tables inside) that ``keys`` refuses."""
    for name in table:
        if name not in keys:
            close = difflib.get_close_matches(name, keys, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise SceneError(f"{where}: unknown key {name!r}; {hint}valid keys are {sorted(keys)}")
    for name, key in keys.items():
        if name not in table:
            if key.required:
                raise SceneError(f"{where}: missing required key {name!r} ({_KIND_NAMES[key.kind]})")
            continue
        value = table[name]
        problem = _type_problem(key.kind, value)
        if problem is None and key.check is not None:
            problem = key.check(value)
        if problem is not None:
            raise SceneError(f"{where}: {name!r} {problem}")
        if key.kind == "table":
            check_table(value, key.keys or {}, f"{where}, {name}")
        elif key.kind == "tables":
            for k, entry in enumerate(value):
                check_table(entry, key.keys or {}, f"{where}, {name}[{k}]{label(entry)}")


def label(entry: dict) -> str:
    name = entry.get("name")
    return f" {name!r}" if isinstance(name, str) else ""


def unique(entries: list[dict], what: str, where: str) -> None:
    seen: set[str | None] = set()
    for entry in entries:
        name = entry.get("name")
        if name in seen:
            raise SceneError(f"{where}: two {what} are named {name!r}; give each a unique name")
        seen.add(name)
