"""The engine knows no application: below the paper's layer (:mod:`ffrf.paper`) no identifier of ``ffrf`` names
the Bennett linkage or the paper, only docstrings and comments may cite them (every formula cites its source).

Identifiers are read from the source with :mod:`ast`: module paths, names of functions, classes, arguments,
variables, attributes, imported names, keyword arguments and every string literal (dict and TOML keys, messages)
that is not a docstring."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: Words of the application; none may appear in an identifier of the engine.
APPLICATION = re.compile("bennett|paper", re.IGNORECASE)
#: Parts of ``ffrf`` above the engine: the application layer, the command line and the package's front.
ABOVE_THE_ENGINE = ("paper", "cli", "cli.py", "__init__.py", "__main__.py")


def _engine_files() -> list[Path]:
    """Every module of ``ffrf`` below the application layer."""
    return [
        path
        for path in sorted((ROOT / "ffrf").rglob("*.py"))
        if path.relative_to(ROOT / "ffrf").parts[0] not in ABOVE_THE_ENGINE
    ]


def _docstrings(tree: ast.Module) -> set[int]:
    """Ids of the string constants that are docstrings: a string standing alone as a statement (a module's,
    class's or function's docstring, or one documenting an attribute for Sphinx)."""
    return {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
    }


def _identifiers(tree: ast.Module) -> list[tuple[int, str]]:
    """(line, text) of every identifier and every string literal but docstrings."""
    docstrings = _docstrings(tree)
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Name):
            found.append((line, node.id))
        elif isinstance(node, ast.Attribute):
            found.append((line, node.attr))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            found.append((line, node.name))
        elif isinstance(node, ast.arg):
            found.append((line, node.arg))
        elif isinstance(node, ast.keyword) and node.arg is not None:
            found.append((line, node.arg))
        elif isinstance(node, ast.alias):
            found += [(line, name) for name in (node.name, node.asname) if name]
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.append((line, node.module))
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            found += [(line, name) for name in node.names]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            found.append((line, node.value))
    return found


def application_words(source: str, where: str = "<source>") -> list[str]:
    """``where:line: text`` of every identifier or non-docstring literal of ``source`` naming the application."""
    tree = ast.parse(source, where)
    return [f"{where}:{line}: {text!r}" for line, text in sorted(_identifiers(tree)) if APPLICATION.search(text)]


@pytest.mark.parametrize("path", _engine_files(), ids=lambda p: str(p.relative_to(ROOT / "ffrf")))
def test_engine_module_names_no_application(path: Path):
    where = str(path.relative_to(ROOT))
    found = ([f"{where}: its path"] if APPLICATION.search(where) else []) + application_words(path.read_text(), where)
    assert not found, f"the engine names the paper's application (move it to ffrf/paper/): {found}"


def test_the_check_sees_an_application_word():
    """The check itself can fail: a function, an argument, a key, a message and an import naming the application
    are found; docstrings and comments citing the paper are not."""
    probe = '''"""Eq. (5) of the paper."""
from ffrf.paper.bennett_scene import VARIANTS  # the Bennett variants


def build_Bennett(paper_variant):
    """The paper's Bennett, Eq. (L1)."""
    return {"bennett": paper_variant, "label": f"Paper {paper_variant}"}
'''
    found = application_words(probe)
    assert {text.split(": ", 1)[1] for text in found} == {
        "'ffrf.paper.bennett_scene'",
        "'build_Bennett'",
        "'paper_variant'",
        "'bennett'",
        "'Paper '",
    }
    assert [text.split(":")[1] for text in found if "'paper_variant'" in text] == ["5", "7", "7"]
    assert application_words('"""The paper\'s Bennett linkage."""\nx = 1  # paper\n') == []
