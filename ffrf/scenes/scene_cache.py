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
"""

from __future__ import annotations

import hashlib
import json
from collections import OrderedDict
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

__all__ = ["LRUCache", "SceneCache", "PROCESS_CACHE", "content_key"]

V = TypeVar("V")

#: Entries each map keeps: FE models are megabytes each (the default P2 6 mm link 10 to 17 MB with its
#: matrices), so 16 of them are four variants of a 4R whose links all differ; a reduced basis is a few MB or less.
FE_ENTRIES = 16
REDUCTION_ENTRIES = 64
MOTION_ENTRIES = 64


class LRUCache(MutableMapping[str, V]):
    """Values by content key, the ``max_entries`` most recently used; ``hits`` counts the values found by
    :meth:`get_or_compute`, ``misses`` those it computed. ``max_entries = 0`` keeps nothing."""

    def __init__(self, max_entries: int) -> None:
        self.max_entries = max_entries
        self._entries: OrderedDict[str, V] = OrderedDict()
        self.hits = 0
        self.misses = 0

    def get_or_compute(self, key: str, compute: Callable[[], V]) -> V:
        """The value under ``key``, else ``compute()``, kept under ``key``."""
        if key in self._entries:
            self.hits += 1
            self._entries.move_to_end(key)
            return self._entries[key]
        self.misses += 1
        value = compute()
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
    """The content-keyed maps of a scene's build (module docstring); ``enabled=False`` keeps nothing."""

    enabled: bool = True
    fe_models: LRUCache[Any] = field(init=False)
    reductions: LRUCache[Any] = field(init=False)
    rigid_motions: LRUCache[Any] = field(init=False)

    def __post_init__(self) -> None:
        on = self.enabled
        self.fe_models = LRUCache(FE_ENTRIES if on else 0)
        self.reductions = LRUCache(REDUCTION_ENTRIES if on else 0)
        self.rigid_motions = LRUCache(MOTION_ENTRIES if on else 0)

    def stats(self) -> dict[str, dict[str, int]]:
        """Hits, misses and entries of each map."""
        maps = {"fe_models": self.fe_models, "reductions": self.reductions, "rigid_motions": self.rigid_motions}
        return {name: {"hits": m.hits, "misses": m.misses, "entries": len(m)} for name, m in maps.items()}

    def clear(self) -> None:
        """Forget every entry and count."""
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
