"""The solver stands alone: importing every module of kinematics/, ffrf/ and identification/
loads neither Exudyn nor NGsolve (they are validation dependencies: pip install .[validation])."""

import pkgutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_solver_modules_load_neither_exudyn_nor_ngsolve():
    modules = [
        info.name
        for package in ("kinematics", "ffrf", "identification")
        for info in pkgutil.walk_packages([str(ROOT / package)], prefix=f"{package}.")
    ]
    modules = [name for name in modules if not name.endswith("__main__")]
    assert len(modules) > 40
    code = (
        "import importlib, sys\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('exudyn', 'ngsolve', 'netgen')))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"
