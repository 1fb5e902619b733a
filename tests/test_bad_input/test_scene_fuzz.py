"""Property: whatever a user does to a valid scene file (drop a key, misspell it, put a wrong type,
nan, inf, a negative, zero or huge value or an empty list in its place), ``load_scene`` either builds
the scene or raises one of the project's own errors; a scene it builds runs to finite results or
stops with the project's own error. Never a raw traceback of numpy or scipy, a hang, or a NaN in a file."""

import json
import math
import re
import tomllib

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from scene_fixtures import PENDULUM, write_bar

from ffrf import load
from ffrf.errors import FEInputError, NewtonDivergence, StaticDivergence
from ffrf.scenes.scene_file import load_scene

PROJECT_ERRORS = (FEInputError, NewtonDivergence, StaticDivergence)
VALID = tomllib.loads(PENDULUM)
REPLACEMENTS = [
    "x",
    "",
    True,
    0,
    -1,
    2,
    0.5,
    -1e-300,
    1e300,
    math.nan,
    math.inf,
    -math.inf,
    [],
    [1.0],
    [0.0, 0.0, 0.0],
    [1.0, "a", 2.0],
    {},
    {"name": "a"},
]
#: A built scene is run only when this small (the property is about errors, not long runs).
MAX_STEPS_TO_RUN = 400


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def to_toml(document: dict) -> str:
    lines = []
    for key, value in document.items():
        if isinstance(value, dict):
            lines += [f"[{toml_key(key)}]"] + [f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for entry in value:
                lines += [f"[[{toml_key(key)}]]"] + [f"{toml_key(k)} = {toml_value(v)}" for k, v in entry.items()]
        else:
            lines.append(f"{toml_key(key)} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


def paths(node, prefix=()):
    """Every (container path, key) in the document: the places a mutation can hit."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else []
    for key, child in items:
        yield prefix, key
        yield from paths(child, prefix + (key,))


def mutate(document: dict, data) -> dict:
    document = json.loads(json.dumps(document))  # deep copy of plain data
    for _ in range(data.draw(st.integers(1, 3))):
        places = list(paths(document))
        prefix, key = data.draw(st.sampled_from(places))
        container = document
        for step in prefix:
            container = container[step]
        action = data.draw(st.sampled_from(["delete", "misspell", "replace"]))
        if isinstance(container, list):
            if action == "delete" and len(container) > 0:
                del container[key]
            else:
                container[key] = data.draw(st.sampled_from(REPLACEMENTS))
        elif action == "delete":
            del container[key]
        elif action == "misspell":
            position = data.draw(st.integers(0, len(key)))
            container[key[:position] + "x" + key[position + 1 :]] = container.pop(key)
        else:
            container[key] = data.draw(st.sampled_from(REPLACEMENTS))
    return document


@settings(
    max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_mutated_scene_gives_a_scene_or_a_project_error(tmp_path, data):
    write_bar(tmp_path)
    document = mutate(VALID, data)
    (tmp_path / "scene.toml").write_text(to_toml(document))
    try:
        scene = load_scene(tmp_path / "scene.toml")
    except FEInputError as error:
        assert "\n" not in str(error)
        event(f"refused: {type(error).__name__}")
        return
    s = scene.settings
    if s.get("mode", "dynamic") == "dynamic" and s.get("t_end", 1.0) / s.get("step", 1e-3) > MAX_STEPS_TO_RUN:
        event("built, too long to run here")
        return
    if s.get("outputs", 101) > MAX_STEPS_TO_RUN:
        event("built, too long to run here")
        return
    try:
        load(scene).run().save(tmp_path / "out")
    except PROJECT_ERRORS as error:
        event(f"run stopped: {type(error).__name__}")
        return
    event("built and ran")
    with np.load(tmp_path / "out" / "results.npz") as results:
        for name in results.files:
            assert np.all(np.isfinite(results[name])), name
