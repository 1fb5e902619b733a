"""Where numba keeps the compiled kernels: a folder named by the kernels' own sources.

numba checks a cached kernel against the source file that defines it only. A kernel that calls a kernel of another
file (``alpha_iterations`` calls ``system_residual``) keeps the callee it was compiled with after that file changes,
and a callee whose signature changed crashes it (``NRT_adapt_ndarray_to_python``: ``descr`` is NULL) or worse. So
the cache lives in ``numba/<digest>`` under the solver's cache folder, the digest a SHA-256 of every kernel source of
the package: any edit of a kernel compiles all of them afresh, in a folder of their own, and a checkout of another
commit finds its own kernels again. This module imports no numba: :mod:`ffrf` sets the folder before numba is
imported, unless ``NUMBA_CACHE_DIR`` is set already.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

__all__ = ["KERNEL_DECORATOR", "default_kernel_cache", "kernel_cache_directory", "kernel_sources"]

#: A line that compiles a kernel: ``@njit``, ``@numba.njit(...)``, ``@jit``.
KERNEL_DECORATOR = re.compile(r"^\s*@(?:numba\.)?n?jit\b", re.MULTILINE)
_PACKAGE = Path(__file__).resolve().parents[1]


def kernel_sources(package: Path = _PACKAGE) -> list[Path]:
    """The package's modules that define numba kernels, in a fixed order."""
    return sorted(path for path in package.rglob("*.py") if KERNEL_DECORATOR.search(path.read_text()))


def kernel_cache_directory(base: Path, package: Path = _PACKAGE) -> Path:
    """``base/numba/<digest>``: the digest (16 hex digits) of the kernel sources' paths and contents."""
    digest = hashlib.sha256()
    for path in kernel_sources(package):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return base / "numba" / digest.hexdigest()[:16]


def default_kernel_cache() -> str:
    """:func:`kernel_cache_directory` under ``$XDG_CACHE_HOME/ffrf`` (else ``~/.cache/ffrf``), created; ``""``
    (numba's own default, next to the sources) where it cannot be created, as in a read-only home. Not under
    ``$FFRF_CACHE_DIR``: that folder is the scenes' and may be ``off``, while compiled kernels are always worth
    keeping. :mod:`ffrf` sets ``NUMBA_CACHE_DIR`` to it unless the user set it."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "ffrf"
    folder = kernel_cache_directory(base)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return ""
    return str(folder)
