"""The disk layer of the scene cache (``ffrf.scenes.scene_cache.DiskStore``): a scene built in a later process
(here: a fresh in-memory cache) reads its meshes, FE models, reductions and rigid motions from disk, and they
equal, to the bit, what building afresh gives; a corrupt or truncated file is recomputed with a warning; a
disabled cache computes and writes nothing.

Every test gives the cache a folder of its own (``tmp_path`` through ``FFRF_CACHE_DIR``), never the user's."""

import logging
import math
import os
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ffrf.paper.bennett_scene import BennettScene, bennett_options, build_bennett_from_options
from ffrf.scenes.linkage_description import BoreError
from ffrf.scenes.scene_cache import CACHE_DIR_VARIABLE, SceneCache, _evict, cache_directory

#: Coarse links (h = 12 mm, P1, 2 modes): the cache does not care about the discretisation.
COARSE: dict[str, Any] = {"h": 0.012, "order": 1, "n_modes": 2}


def _build(cache: SceneCache) -> BennettScene:
    """The paper's PLA Bennett, coarse, the base's joint-3 bore twisted by 0.3 deg."""
    options = replace(
        bennett_options("pla", **COARSE), bore_errors=(BoreError(joint=3, link=0, twist=math.radians(0.3)),)
    )
    return build_bennett_from_options(options, cache=cache)


def _assert_same_bits(a: BennettScene, b: BennettScene) -> None:
    """Every array a run takes from the build is equal bit for bit (FE model, basis, body, markers, start)."""
    for x, y in zip(a.bodies, b.bodies, strict=True):
        np.testing.assert_array_equal(x.fe.nodes, y.fe.nodes)
        for matrix in ("mass", "stiffness"):
            for part in ("data", "indices", "indptr"):
                np.testing.assert_array_equal(
                    getattr(getattr(x.fe, matrix), part), getattr(getattr(y.fe, matrix), part)
                )
        np.testing.assert_array_equal(x.reduction.basis, y.reduction.basis)
        np.testing.assert_array_equal(x.body.stiffness, y.body.stiffness)
        np.testing.assert_array_equal(x.body.damping, y.body.damping)
        for moment in fields(x.body.moments):
            np.testing.assert_array_equal(getattr(x.body.moments, moment.name), getattr(y.body.moments, moment.name))
        assert x.interfaces.keys() == y.interfaces.keys() and x.markers.keys() == y.markers.keys()
        for name in x.interfaces:
            np.testing.assert_array_equal(x.interfaces[name].nodes, y.interfaces[name].nodes)
            np.testing.assert_array_equal(x.interfaces[name].weights, y.interfaces[name].weights)
    np.testing.assert_array_equal(a.q_initial, b.q_initial)
    np.testing.assert_array_equal(a.start_phi, b.start_phi)


def _files(folder: Path) -> list[Path]:
    return sorted(folder.glob("*.pkl"))


def test_the_folder_follows_the_variable_else_xdg_else_home(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path / "mine"))
    assert cache_directory() == tmp_path / "mine"
    for off in ("off", "OFF", "0", "none"):
        monkeypatch.setenv(CACHE_DIR_VARIABLE, off)
        assert cache_directory() is None
    monkeypatch.delenv(CACHE_DIR_VARIABLE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_directory() == tmp_path / "xdg" / "ffrf"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_directory() == tmp_path / "home" / ".cache" / "ffrf"


def test_a_later_process_reads_from_disk_what_building_afresh_gives_bit_for_bit(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path))
    first = SceneCache()
    computed = _build(first)
    assert {m["misses"] for m in first.stats().values()} != {0} and len(_files(tmp_path)) == 4 + 4 + 2
    later = SceneCache()  # a new process: nothing in memory
    read = _build(later)
    stats = later.stats()
    assert stats["fe_models"]["disk_hits"] == 4 and stats["reductions"]["disk_hits"] == 4
    assert stats["rigid_motions"]["disk_hits"] == 2 and sum(m["misses"] for m in stats.values()) == 0
    fresh = _build(SceneCache(enabled=False))
    _assert_same_bits(read, fresh)
    _assert_same_bits(computed, fresh)


def test_bodies_reduced_in_threads_are_those_reduced_one_by_one(monkeypatch):
    """The four links reduced at once in threads (one link per thread, while the next links are meshed), one after
    the other in one thread, and each alone in the building thread (as links above THREADED_REDUCTION_DOFS are):
    every array of the build equal bit for bit, whatever the machine's cores."""
    from ffrf.scenes import builder

    monkeypatch.setattr(builder, "REDUCTION_THREADS", 4)
    threaded = _build(SceneCache(enabled=False))
    monkeypatch.setattr(builder, "REDUCTION_THREADS", 1)
    _assert_same_bits(threaded, _build(SceneCache(enabled=False)))
    monkeypatch.setattr(builder, "THREADED_REDUCTION_DOFS", 0)
    _assert_same_bits(threaded, _build(SceneCache(enabled=False)))


@pytest.mark.parametrize("damage", ["truncated", "flipped byte", "empty"])
def test_a_corrupt_file_is_recomputed_with_a_one_line_warning(monkeypatch, tmp_path, caplog, damage):
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path))
    _build(SceneCache())
    broken = [path for path in _files(tmp_path) if path.name.startswith("reductions-")][0]
    data = broken.read_bytes()
    if damage == "truncated":  # as a process killed while writing would leave it, without the atomic rename
        broken.write_bytes(data[: len(data) // 2])
    elif damage == "flipped byte":
        broken.write_bytes(data[:-100] + bytes([data[-100] ^ 0xFF]) + data[-99:])
    else:
        broken.write_bytes(b"")
    cache = SceneCache()
    with caplog.at_level(logging.WARNING, logger="ffrf.scenes.scene_cache"):
        rebuilt = _build(cache)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and broken.name in warnings[0] and "recomputing" in warnings[0]
    assert cache.stats()["reductions"] == {"hits": 0, "disk_hits": 3, "misses": 1, "entries": 4}
    _assert_same_bits(rebuilt, _build(SceneCache(enabled=False)))
    assert broken.read_bytes() == data  # written again, whole


def test_a_disabled_cache_computes_and_writes_nothing(monkeypatch, tmp_path):
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setenv(CACHE_DIR_VARIABLE, "off")
    off = SceneCache()
    _build(off)
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path / "cache"))
    memory_only = SceneCache(persistent=False)
    _build(memory_only)
    assert not any(tmp_path.rglob("*"))
    for cache in (off, memory_only):
        assert sum(m["disk_hits"] for m in cache.stats().values()) == 0 and cache.stats()["fe_models"]["misses"] == 4


def test_the_least_recently_used_files_go_beyond_the_size_limit(tmp_path):
    for k, name in enumerate(("old", "middle", "new")):
        path = tmp_path / f"{name}.pkl"
        path.write_bytes(bytes(100))
        os.utime(path, (1_000_000 + k, 1_000_000 + k))
    _evict(tmp_path, 250)
    assert [p.stem for p in _files(tmp_path)] == ["middle", "new"]
