"""The numba cache folder is named by the kernels' sources (:mod:`ffrf.numerics.kernel_cache`): a change of any
kernel's file gives another folder, a change elsewhere the same, and a user's ``NUMBA_CACHE_DIR`` is kept; numba
imported before ffrf gets the folder too."""

import os
import subprocess
import sys
from pathlib import Path

from ffrf.numerics.kernel_cache import kernel_cache_directory, kernel_sources

ROOT = Path(__file__).resolve().parents[2]


def _package(tmp_path: Path) -> Path:
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "kernels.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x\n")
    (package / "sub" / "more.py").write_text("import numba\n\n\n@numba.njit\ndef g(x):\n    return f(x)\n")
    (package / "plain.py").write_text("def h(x):\n    return x  # mentions numba, compiles nothing\n")
    return package


def test_only_modules_that_compile_kernels_are_sources(tmp_path):
    package = _package(tmp_path)
    assert [p.relative_to(package).as_posix() for p in kernel_sources(package)] == ["kernels.py", "sub/more.py"]


def test_the_folder_changes_with_a_kernel_source_and_only_then(tmp_path):
    package = _package(tmp_path)
    first = kernel_cache_directory(tmp_path / "cache", package)
    assert first.parent == tmp_path / "cache" / "numba" and len(first.name) == 16
    (package / "plain.py").write_text("def h(x):\n    return 2 * x\n")
    assert kernel_cache_directory(tmp_path / "cache", package) == first
    (package / "sub" / "more.py").write_text("import numba\n\n\n@numba.njit\ndef g(x):\n    return f(x) + 1\n")
    assert kernel_cache_directory(tmp_path / "cache", package) != first


def test_importing_ffrf_sets_the_folder_unless_the_user_did(tmp_path):
    code = "import os, ffrf; print(os.environ['NUMBA_CACHE_DIR'])"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(tmp_path), PYTHONPATH=str(ROOT))
    chosen = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    expected = kernel_cache_directory(tmp_path / "ffrf")
    assert Path(chosen.stdout.strip()) == expected and expected.is_dir()
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    kept = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert kept.stdout.strip() == str(tmp_path / "mine")


def test_numba_imported_first_still_gets_the_folder(tmp_path):
    """A script that imports numba before ffrf: numba has read its settings already, and its own default cache (next
    to the sources, checked per file) would keep a kernel's stale callees."""
    code = "import numba, ffrf; print(numba.core.config.CACHE_DIR)"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(tmp_path), PYTHONPATH=str(ROOT))
    chosen = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert Path(chosen.stdout.strip()) == kernel_cache_directory(tmp_path / "ffrf")
