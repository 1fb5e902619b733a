"""The layers of ``docs/architecture.md``, enforced: a module of ``ffrf`` imports only from its own
layer or lower ones, integrators do not import each other, and the project's packages stack as
kinematics -> ffrf -> identification -> validation (validation may use them all; none uses it).

Imports are read from the source with :mod:`ast`, including imports inside functions, so a
deferred import cannot hide a cycle."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: Layers of ffrf, lowest first; a module may import from layers at or below its own rank.
FFRF_LAYERS: dict[str, int] = {
    "errors": 0,
    "numerics": 0,
    "mesh": 1,
    "geometry": 2,
    "fe": 2,
    "reduction": 3,
    "body": 4,
    "system": 5,
    "solvers": 6,
    "output": 7,
    "scenes": 8,
    "studies": 9,
    "model": 10,
    "paper": 11,
    "cli": 12,
    "__init__": 12,
    "__main__": 12,
}
#: Packages of the project, lowest first.
PACKAGES: dict[str, int] = {"kinematics": 0, "ffrf": 1, "identification": 2, "validation": 3}
INTEGRATORS = {"generalized_alpha", "variational_midpoint", "static_solver"}


def _imports(path: Path, package: str | None = None) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``path`` (a module of ``package``, by
    default the one its place under the repository says)."""
    package = package or ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            found.append((node.lineno, module))
            if node.module is None or node.level:  # "from . import x" or "from .pkg import x": x may be a module
                found += [(node.lineno, f"{module}.{alias.name}") for alias in node.names]
    return found


def _layer(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "ffrf":
        return None
    return parts[1] if len(parts) > 1 else "__init__"


def _ffrf_files() -> list[Path]:
    return sorted((ROOT / "ffrf").rglob("*.py"))


def test_every_ffrf_module_sits_in_a_known_layer():
    unknown = {
        str(p.relative_to(ROOT))
        for p in _ffrf_files()
        if (p.parent.name if p.parent.name != "ffrf" else p.stem) not in FFRF_LAYERS
    }
    assert not unknown, f"modules outside the layers of docs/architecture.md: {sorted(unknown)}"


@pytest.mark.parametrize("path", _ffrf_files(), ids=lambda p: str(p.relative_to(ROOT / "ffrf")))
def test_ffrf_module_imports_no_higher_layer(path: Path):
    own = path.parent.name if path.parent.name != "ffrf" else path.stem
    violations = [
        f"line {line}: {module} ({layer}, rank {FFRF_LAYERS[layer]})"
        for line, module in _imports(path)
        if (layer := _layer(module)) is not None and layer in FFRF_LAYERS and FFRF_LAYERS[layer] > FFRF_LAYERS[own]
    ]
    assert not violations, (
        f"{path.relative_to(ROOT)} (layer {own}, rank {FFRF_LAYERS[own]}) imports upwards: {violations}"
    )


def test_integrators_do_not_import_each_other():
    for name in INTEGRATORS:
        path = ROOT / "ffrf" / "solvers" / f"{name}.py"
        others = [m for _, m in _imports(path) if m.split(".")[-1] in INTEGRATORS - {name}]
        assert not others, f"{name} imports {others}; shared pieces belong in ffrf/solvers/common.py"


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_packages_import_no_higher_package(package: str):
    violations = [
        f"{path.relative_to(ROOT)}:{line}: {module}"
        for path in sorted((ROOT / package).rglob("*.py"))
        for line, module in _imports(path)
        if module.split(".")[0] in PACKAGES and PACKAGES[module.split(".")[0]] > PACKAGES[package]
    ]
    assert not violations, violations


def test_the_layer_check_sees_a_violation(tmp_path):
    """The check itself can fail: upward imports, absolute, relative and deferred into a function,
    written into a module of the mesh layer, are all found."""
    probe = tmp_path / "probe.py"
    probe.write_text(
        "from ..scenes import scene_file\n\ndef f():\n    from ffrf.solvers.static_solver import quasi_static\n"
    )
    imported = {m for _, m in _imports(probe, package="ffrf.mesh")}
    assert {"ffrf.scenes.scene_file", "ffrf.solvers.static_solver"} <= imported
    assert all(FFRF_LAYERS[_layer(m)] > FFRF_LAYERS["mesh"] for m in imported if m.startswith("ffrf."))


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph(root: Path, packages: list[str]) -> dict[str, set[str]]:
    """Module -> the project's modules it imports (at any depth: inside functions and ``TYPE_CHECKING`` blocks
    too). A submodule's import of its own package's ``__init__`` is not an edge: the package imports its parts."""
    files = {_module_name(p, root): p for package in packages for p in sorted((root / package).rglob("*.py"))}
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges = set()
        for _, module in _imports(path, package=package):
            while module and module not in files:  # "ffrf.x.y.Name" -> the module "ffrf.x.y"
                module = module.rpartition(".")[0]
            if module and module != name and not name.startswith(module + "."):
                edges.add(module)
        graph[name] = edges
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle_in_any_package():
    """No two modules of the project import each other, directly or around a circle, even through an import
    inside a function or under ``TYPE_CHECKING`` (which would only hide the circle)."""
    cycles = _cycles(_import_graph(ROOT, sorted(PACKAGES)))
    assert not cycles, f"import cycles: {cycles}; move what both sides need into a module below them"


def test_the_cycle_check_sees_a_cycle(tmp_path):
    """The check itself can fail: a circle closed by an import inside a function and one closed under
    ``TYPE_CHECKING`` are both found; a submodule importing its own package is not a circle."""
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("from . import a\n")
    (package / "a.py").write_text("import pkg\nfrom pkg.b import g\n")
    (package / "b.py").write_text("def g():\n    from pkg.c import h\n")
    (package / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import x\n")
    (package / "d.py").write_text("from pkg import a\n")
    assert _cycles(_import_graph(tmp_path, ["pkg"])) == [["pkg.a", "pkg.b", "pkg.c"]]
