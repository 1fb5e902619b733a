"""A disk cache file holds its whole key and is checked on read (``ffrf.scenes.scene_cache``, issue #32): a file of
another scene copied over this scene's file is recomputed, never used. Before, the checksum covered only the bytes:
the E = 1.2 GPa scene returned the E = 2.4 GPa scene's matrices bit for bit.

Every test gives the cache a folder of its own (``tmp_path`` through ``FFRF_CACHE_DIR``)."""

import logging
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np

from ffrf.paper.bennett_scene import BennettScene, bennett_options, build_bennett_from_options
from ffrf.scenes.scene_cache import _MISSING, CACHE_DIR_VARIABLE, DiskStore, SceneCache


def _build(young: float, cache: SceneCache) -> BennettScene:
    """The paper's PLA Bennett, coarse (h = 12 mm, P1, 2 modes), with Young's modulus ``young`` (Pa)."""
    options = bennett_options("pla", h=0.012, order=1, n_modes=2)
    options = replace(options, material=replace(options.material, E=young))
    return build_bennett_from_options(options, cache=cache)


def _stiffness(scene: BennettScene) -> list[np.ndarray]:
    return [body.body.stiffness for body in scene.bodies]


def _by_age(folder: Path, kind: str) -> list[Path]:
    """The files of map ``kind`` in ``folder``, oldest first (a build writes them link by link)."""
    return sorted(folder.glob(f"{kind}-*.pkl"), key=lambda path: path.stat().st_mtime_ns)


def test_another_scenes_file_copied_over_this_scenes_file_is_recomputed(monkeypatch, tmp_path, caplog):
    """Scene B (E = 1.2 GPa) finds scene A's (E = 2.4 GPa) FE models and reductions under its own file names: it
    recomputes every one with a warning each, and its bodies equal those of a build without cache, not A's."""
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path / "a"))
    scene_a = _build(2.4e9, SceneCache())
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path / "b"))
    _build(1.2e9, SceneCache())
    copied = 0
    for kind in ("fe_models", "reductions"):  # link k's file of A over link k's of B (both written link by link)
        ours, theirs = (_by_age(folder, kind) for folder in (tmp_path / "b", tmp_path / "a"))
        assert len(ours) == len(theirs) == 4 and {p.name for p in ours}.isdisjoint(p.name for p in theirs)
        for mine, other in zip(ours, theirs, strict=True):
            shutil.copyfile(other, mine)
            copied += 1
    cache = SceneCache()
    with caplog.at_level(logging.WARNING, logger="ffrf.scenes.scene_cache"):
        scene_b = _build(1.2e9, cache)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == copied and all("another entry" in w and "recomputing" in w for w in warnings)
    assert cache.stats()["fe_models"]["misses"] == 4 and cache.stats()["reductions"]["misses"] == 4
    fresh = _build(1.2e9, SceneCache(enabled=False))
    for b, f, a in zip(_stiffness(scene_b), _stiffness(fresh), _stiffness(scene_a), strict=True):
        np.testing.assert_array_equal(b, f)
        assert not np.array_equal(b, a)
    # stiffness ~ E: the modal stiffness of B is half of A's (same mesh, same modes up to sign)
    np.testing.assert_allclose(np.diag(_stiffness(scene_b)[1]), 0.5 * np.diag(_stiffness(scene_a)[1]), rtol=1e-9)


def test_a_file_whose_stored_key_differs_from_its_name_is_detected_and_deleted(monkeypatch, tmp_path, caplog):
    monkeypatch.setenv(CACHE_DIR_VARIABLE, str(tmp_path))
    store = DiskStore("reductions")
    store.save("key-one", {"value": 1.0})
    first, second = store.path("key-one"), store.path("key-two")
    assert isinstance(first, Path) and isinstance(second, Path)
    shutil.copyfile(first, second)  # key-one's value under key-two's name
    with caplog.at_level(logging.WARNING, logger="ffrf.scenes.scene_cache"):
        assert store.load("key-two") is _MISSING
    (message,) = [r.getMessage() for r in caplog.records]
    assert second.name in message and "key key-one" in message and "instead of key-two" in message
    assert not second.exists() and store.load("key-one") == {"value": 1.0}
    # a file of the same key but another map or code version is refused the same way
    shutil.copyfile(first, DiskStore("fe_models").path("key-one"))
    assert DiskStore("fe_models").load("key-one") is _MISSING
