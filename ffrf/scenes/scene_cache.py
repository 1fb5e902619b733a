r"""What building a scene computes, kept by content so that a scene built again pays only for what differs.

A study builds thousands of variants that differ in a few bores or a material: their links' meshes, FE
matrices, reductions and the rigid loop's motion are mostly those of the variant before. :class:`SceneCache`
holds them in bounded least-recently-used maps (:class:`LRUCache`), each entry under a key of its input's
*content* (:func:`content_key`: SHA-256 of canonical JSON, floats written exactly), never of an object's
identity or name, so a hit returns what the uncached path would compute, to the bit:

* ``fe_models``: a body's FE model, interfaces and parametric geometry
  (:class:`ffrf.scenes.builder.MeshedBody`), keyed by the body's description without what does not enter them
  (pose, start velocity, modes, reduction kind) and the content of the files it reads
  (:func:`ffrf.scenes.builder.build_scene`);
* ``reductions``: reduced bases with their modal moments and interface markers
  (:class:`ffrf.scenes.builder.Reduced`) by :func:`ffrf.reduction.reduced_io.reduction_fingerprint` (nodes, M,
  K, interfaces, modes);
* ``rigid_motions``: the rigid loop's start pose and the drive's range checked along it
  (:func:`ffrf.scenes.linkage_scene.build_linkage`) and the ideal coupler path a run is compared with
  (:meth:`ffrf.scenes.linkage_scene.LinkageScene.ideal_coupler_points`), keyed by the loop's axes, the driver, the
  start and the angles.

Every process has one, :data:`PROCESS_CACHE`, which the builders use unless given another (a Dask worker keeps
it between the variants it runs); ``SceneCache(enabled=False)`` builds everything afresh.

**On disk, between processes.** A value computed afresh is also written to a folder (:func:`cache_directory`:
``$FFRF_CACHE_DIR``, else ``$XDG_CACHE_HOME/ffrf``, else ``~/.cache/ffrf``; ``FFRF_CACHE_DIR=off`` keeps nothing on
disk) by :class:`DiskStore`, and a later process with the same content reads it back instead of meshing, assembling
and reducing again. A file's name is the SHA-256 of :data:`DISK_FORMAT`, :func:`code_version` (the solver's sources
and the versions of the libraries that compute the values: a changed code computes afresh), the map's name and the
content key. The file holds a header with that whole identity again (format, map, content key, code version, and the
library versions readably) and the SHA-256 of identity and payload, and a read compares the identity with the one
asked for: a file copied or renamed over another's name (another scene's values under this scene's key) is detected
like a truncated or corrupt one, deleted with a one-line warning and recomputed. The payload is a pickle, which is
exact for arrays and floats (a hit is, bit for bit, what the computation gives) and trusted as numba's cache is: the
folder is the user's own. Writes are atomic (a temporary file, then :func:`os.replace`), so processes running side
by side never read a partial file; the folder is kept under :data:`DISK_BYTES` by deleting the files least recently
used.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import importlib.util
import json
import logging
import os
import pickle
import sys
import tempfile
from collections import OrderedDict
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

__all__ = [
    "CACHE_DIR_VARIABLE",
    "DiskStore",
    "LRUCache",
    "SceneCache",
    "PROCESS_CACHE",
    "cache_directory",
    "code_version",
    "content_key",
    "library_versions",
]

log = logging.getLogger(__name__)

V = TypeVar("V")

#: Entries each map keeps: FE models are megabytes each (the default P2 6 mm link 10 to 17 MB with its
#: matrices), so 16 of them are four variants of a 4R whose links all differ; a reduced basis is a few MB or less.
FE_ENTRIES = 16
REDUCTION_ENTRIES = 64
MOTION_ENTRIES = 64

#: The environment variable that moves the disk cache (a folder) or turns it off (``off``, ``none``, ``0``).
CACHE_DIR_VARIABLE = "FFRF_CACHE_DIR"
_OFF = ("off", "none", "0", "false", "no")
#: Bump when what a disk file holds, or how, changes: every older file is then ignored.
DISK_FORMAT = "ffrf-scene-cache-2"
#: Bytes of files the disk cache keeps: the default scene writes about 60 MB (four FE models and their bases).
DISK_BYTES = 2 * 1024**3
#: The packages whose sources compute the cached values, and the libraries whose versions can change them.
_SOURCES = ("ffrf", "kinematics")
_LIBRARIES = ("numpy", "scipy", "scikit-fem", "gmsh", "numba")
_MISSING = object()


def cache_directory() -> Path | None:
    """The disk cache's folder: ``$FFRF_CACHE_DIR`` (``None`` if it says ``off``), else ``$XDG_CACHE_HOME/ffrf``,
    else ``~/.cache/ffrf``; read at each use, so a test or a ``--no-cache`` run can change it."""
    value = os.environ.get(CACHE_DIR_VARIABLE, "").strip()
    if value.lower() in _OFF:
        return None
    if value:
        return Path(value).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "ffrf"


@functools.cache
def library_versions() -> str:
    """The Python version and the versions of :data:`_LIBRARIES`, as text (``numpy=2.1.3;scipy=...``)."""
    versions = [f"python={sys.version.split()[0]}"]
    for library in _LIBRARIES:
        try:
            versions.append(f"{library}={importlib.metadata.version(library)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(f"{library}=none")
    return ";".join(versions)


@functools.cache
def code_version() -> str:
    """SHA-256 (hex) of the Python version, the versions of :data:`_LIBRARIES` and the bytes of every source file
    of :data:`_SOURCES`: what, besides a value's input, decides its bits (a disk file of other code is not read)."""
    digest = hashlib.sha256(sys.version.encode())
    for library in _LIBRARIES:
        try:
            digest.update(f"{library}={importlib.metadata.version(library)};".encode())
        except importlib.metadata.PackageNotFoundError:
            digest.update(f"{library}=none;".encode())
    for package in _SOURCES:
        spec = importlib.util.find_spec(package)
        root = Path(next(iter(spec.submodule_search_locations or []))) if spec else Path(package)
        for path in sorted(root.rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


@dataclass(frozen=True)
class DiskStore:
    """One map's values in :func:`cache_directory`, a file per content key (module docstring): ``load`` gives
    :data:`_MISSING` when there is no readable file, ``save`` writes one atomically; neither ever raises for the
    cache's sake (a broken file or a read-only folder is a warning, and the value is computed)."""

    name: str

    def path(self, key: str) -> Path | None:
        """The file of ``key`` (``None`` when the disk cache is off)."""
        folder = cache_directory()
        if folder is None:
            return None
        name = hashlib.sha256(f"{DISK_FORMAT};{code_version()};{self.name};{key}".encode()).hexdigest()
        return folder / f"{self.name}-{name}.pkl"

    def identity(self, key: str) -> dict[str, str]:
        """What the file of ``key`` is for, written into it and compared on read (its name is a hash of all but the
        libraries, which the code version covers and are here to be read): format, map, content key, code version
        (:func:`code_version`) and library versions (:func:`library_versions`)."""
        return {
            "format": DISK_FORMAT,
            "map": self.name,
            "key": key,
            "code": code_version(),
            "libraries": library_versions(),
        }

    def load(self, key: str) -> Any:
        """The value stored under ``key``, else :data:`_MISSING` (a corrupt file is deleted with a warning)."""
        path = self.path(key)
        if path is None or not path.is_file():
            return _MISSING
        try:
            value = _unpacked(path.read_bytes(), self.identity(key))
            os.utime(path)  # recently used: the last to be evicted
            return value
        except Exception as error:  # noqa: BLE001 -- whatever a broken file raises, the run recomputes
            log.warning("scene cache: %s is unreadable (%s); recomputing it", path, error)
            path.unlink(missing_ok=True)
            return _MISSING

    def save(self, key: str, value: Any) -> None:
        """Write ``value`` under ``key`` (temporary file, then :func:`os.replace`), then evict beyond
        :data:`DISK_BYTES`; a folder that cannot be written is a warning."""
        path = self.path(key)
        if path is None:
            return
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            handle, temporary = tempfile.mkstemp(prefix=".tmp-", dir=path.parent)
            try:
                with os.fdopen(handle, "wb") as stream:
                    stream.write(_packed(value, self.identity(key)))
                os.replace(temporary, path)
            except BaseException:
                Path(temporary).unlink(missing_ok=True)
                raise
            _evict(path.parent, DISK_BYTES)
        except OSError as error:
            log.warning("scene cache: cannot write %s (%s); continuing without it", path, error)


def _packed(value: Any, identity: dict[str, str]) -> bytes:
    """The bytes of a disk file: :data:`DISK_FORMAT`, the ``identity`` (:meth:`DiskStore.identity`, one JSON line),
    the SHA-256 of identity line and payload, the payload (a pickle)."""
    payload = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    line = json.dumps(identity, sort_keys=True).encode()
    digest = hashlib.sha256(line + b"\n" + payload).hexdigest()
    return f"{DISK_FORMAT}\n".encode() + line + f"\n{digest}\n".encode() + payload


def _unpacked(data: bytes, identity: dict[str, str]) -> Any:
    """The value of :func:`_packed` bytes written for ``identity``; ``ValueError`` if the format, the identity (a
    file of another key, map or code under this name) or the checksum does not match."""
    head, _, rest = data.partition(b"\n")
    line, _, rest = rest.partition(b"\n")
    digest, _, payload = rest.partition(b"\n")
    if head.decode(errors="replace") != DISK_FORMAT:
        raise ValueError(f"format {head[:40]!r}, expected {DISK_FORMAT!r}")
    if hashlib.sha256(line + b"\n" + payload).hexdigest() != digest.decode(errors="replace"):
        raise ValueError("checksum mismatch: truncated or corrupt")
    stored = json.loads(line)
    differs = sorted(k for k in identity.keys() | stored.keys() if stored.get(k) != identity.get(k))
    if differs:
        shown = ", ".join(f"{k} {str(stored.get(k))[:12]} instead of {str(identity.get(k))[:12]}" for k in differs)
        raise ValueError(f"it holds another entry ({shown}), copied or renamed over this one")
    return pickle.loads(payload)


def _evict(folder: Path, max_bytes: int) -> None:
    """Delete the least recently used cache files of ``folder`` until the rest fit in ``max_bytes``."""
    files = []
    for path in folder.glob("*.pkl"):
        try:
            status = path.stat()
        except FileNotFoundError:  # another process evicted it
            continue
        files.append((status.st_mtime, status.st_size, path))
    total = sum(size for _, size, _ in files)
    for _, size, path in sorted(files, key=lambda f: f[0]):
        if total <= max_bytes:
            break
        path.unlink(missing_ok=True)
        total -= size


class LRUCache(MutableMapping[str, V]):
    """Values by content key, the ``max_entries`` most recently used, and, with ``disk``, every value computed
    also on disk for later processes; ``hits`` counts the values :meth:`get_or_compute` found in memory,
    ``disk_hits`` those it read from disk, ``misses`` those it computed. ``max_entries = 0`` keeps nothing."""

    def __init__(self, max_entries: int, disk: DiskStore | None = None) -> None:
        self.max_entries = max_entries
        self.disk = disk
        self._entries: OrderedDict[str, V] = OrderedDict()
        self.hits = 0
        self.disk_hits = 0
        self.misses = 0

    def get_or_compute(self, key: str, compute: Callable[[], V]) -> V:
        """The value under ``key`` in memory, else on disk, else ``compute()`` (then also written to disk), kept
        under ``key``."""
        if key in self._entries:
            self.hits += 1
            self._entries.move_to_end(key)
            return self._entries[key]
        value: Any = self.disk.load(key) if self.disk is not None else _MISSING
        if value is _MISSING:
            self.misses += 1
            value = compute()
            if self.disk is not None:
                self.disk.save(key, value)
        else:
            self.disk_hits += 1
        self[key] = value
        return value

    def __getitem__(self, key: str) -> V:
        value = self._entries[key]
        self._entries.move_to_end(key)
        return value

    def __setitem__(self, key: str, value: V) -> None:
        self._entries[key] = value
        self._entries.move_to_end(key)
        while len(self._entries) > self.max_entries:
            self._entries.popitem(last=False)

    def __delitem__(self, key: str) -> None:
        del self._entries[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)


@dataclass
class SceneCache:
    """The content-keyed maps of a scene's build (module docstring); ``enabled=False`` keeps nothing,
    ``persistent=False`` keeps them in memory only (``FFRF_CACHE_DIR=off`` does so for every cache)."""

    enabled: bool = True
    persistent: bool = True
    fe_models: LRUCache[Any] = field(init=False)
    reductions: LRUCache[Any] = field(init=False)
    rigid_motions: LRUCache[Any] = field(init=False)

    def __post_init__(self) -> None:
        on, disk = self.enabled, self.enabled and self.persistent
        self.fe_models = LRUCache(FE_ENTRIES if on else 0, DiskStore("fe_models") if disk else None)
        self.reductions = LRUCache(REDUCTION_ENTRIES if on else 0, DiskStore("reductions") if disk else None)
        self.rigid_motions = LRUCache(MOTION_ENTRIES if on else 0, DiskStore("rigid_motions") if disk else None)

    def stats(self) -> dict[str, dict[str, int]]:
        """Hits (in memory), disk hits, misses and entries of each map."""
        maps = {"fe_models": self.fe_models, "reductions": self.reductions, "rigid_motions": self.rigid_motions}
        return {
            name: {"hits": m.hits, "disk_hits": m.disk_hits, "misses": m.misses, "entries": len(m)}
            for name, m in maps.items()
        }

    def clear(self) -> None:
        """Forget every entry and count in memory (the disk files stay)."""
        self.__post_init__()


def _plain(value: Any) -> Any:
    """Arrays and numpy scalars as lists and Python numbers, for JSON."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"content_key cannot encode {type(value).__name__}")


def content_key(*parts: Any) -> str:
    """SHA-256 (hex) of ``parts`` as canonical JSON (sorted keys; floats in their shortest exact form, so two
    keys are equal exactly when the numbers are; arrays as nested lists)."""
    text = json.dumps(parts, sort_keys=True, default=_plain, allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()


#: This process's cache (module docstring).
PROCESS_CACHE = SceneCache()
