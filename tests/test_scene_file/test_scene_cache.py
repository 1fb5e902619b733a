"""The content-keyed scene cache (``ffrf.scenes.scene_cache``): what a scene built again takes from it equals what
building it afresh gives, to the bit, and a changed input (a file's content, a bore, one ulp of a number) is never
served a stale entry.

Truth is the uncached build (``SceneCache(enabled=False)``), and, for what must be rebuilt, the inputs themselves:
a bore error remeshes only the link that carries it; a mesh file rewritten under the same name is read again."""

import math
import tomllib
from dataclasses import replace
from typing import Any

import meshio
import numpy as np
from scene_fixtures import PENDULUM, write_bar

from ffrf import load
from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
from ffrf.scenes.builder import build_scene
from ffrf.scenes.linkage_description import BoreError
from ffrf.scenes.linkage_run import PATH_SENSORS
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.scene_cache import LRUCache, SceneCache, content_key
from kinematics import BennettLinkage, SingleLoop

#: Coarse links (h = 12 mm, P1, 2 modes): the cache does not care about the discretisation.
COARSE: dict[str, Any] = {"h": 0.012, "order": 1, "n_modes": 2}


def _options(twist_deg: float = 0.0, model: str = "misfit"):
    """The paper's PLA Bennett, coarse, the base's joint-3 bore twisted by ``twist_deg`` as ``model`` builds it."""
    errors = (BoreError(joint=3, link=0, twist=math.radians(twist_deg)),) if twist_deg else ()
    return replace(bennett_options("pla", **COARSE), bore_errors=errors, bore_error_model=model)


def test_the_cache_keeps_the_most_recently_used_entries_and_counts_hits_and_misses():
    cache: LRUCache[int] = LRUCache(max_entries=2)
    assert cache.get_or_compute("a", lambda: 1) == 1
    assert cache.get_or_compute("b", lambda: 2) == 2
    assert cache.get_or_compute("a", lambda: 10) == 1  # found: "a" is now the most recent
    assert cache.get_or_compute("c", lambda: 3) == 3  # "b", the least recently used, goes
    assert sorted(cache) == ["a", "c"] and (cache.hits, cache.misses) == (1, 3)
    assert cache.get_or_compute("b", lambda: 20) == 20
    nothing: LRUCache[int] = LRUCache(max_entries=0)
    assert nothing.get_or_compute("a", lambda: 1) == 1 and len(nothing) == 0


def test_content_keys_are_equal_exactly_when_the_content_is():
    values = np.array([0.1, 0.2, 0.3])
    assert content_key("x", {"a": 1.0, "b": values}) == content_key("x", {"b": values.copy(), "a": 1.0})
    assert content_key("x", 0.1) != content_key("x", float(np.nextafter(0.1, 1.0)))  # one ulp apart
    assert content_key("x", values) != content_key("x", values[::-1])


def test_a_variant_built_from_a_warm_cache_equals_one_built_afresh():
    """The misfit model keeps the nominal meshes: the second variant's four links, their reductions and the rigid
    start all come from the cache (identical objects), and its run equals an uncached build's bit for bit."""
    cache = SceneCache()
    first = build_bennett_from_options(_options(0.3), cache=cache)
    warm = build_bennett_from_options(_options(-0.4), cache=cache)
    assert cache.stats()["fe_models"] == {"hits": 4, "disk_hits": 0, "misses": 4, "entries": 4}
    assert cache.stats()["reductions"]["hits"] == 4 and cache.stats()["rigid_motions"]["hits"] == 2
    assert all(a.fe is b.fe and a.reduction is b.reduction for a, b in zip(first.bodies, warm.bodies, strict=True))
    cold = build_bennett_from_options(_options(-0.4), cache=SceneCache(enabled=False))
    np.testing.assert_array_equal(warm.q_initial, cold.q_initial)
    np.testing.assert_array_equal(warm.start_phi, cold.start_phi)
    runs = [load(scene).run(mode="quasi_static", outputs=9) for scene in (warm, cold)]
    assert runs[0].sensors.keys() == runs[1].sensors.keys()
    for name, values in runs[0].sensors.items():
        np.testing.assert_array_equal(values, runs[1].sensors[name], err_msg=name)
    assert runs[0].metadata["assembly"] == runs[1].metadata["assembly"]


def test_a_remeshed_bore_rebuilds_only_the_link_that_carries_it():
    """With ``bore_error_model = "remesh"`` the base (link 0) is meshed on its twisted bore: its FE model is new,
    the other three links' come from the cache."""
    cache = SceneCache()
    nominal = build_bennett_from_options(_options(0.0, "remesh"), cache=cache)
    twisted = build_bennett_from_options(_options(1.0, "remesh"), cache=cache)
    assert cache.stats()["fe_models"]["hits"] == 3
    assert nominal.bodies[0].fe is not twisted.bodies[0].fe
    assert not np.array_equal(nominal.bodies[0].fe.nodes, twisted.bodies[0].fe.nodes)
    assert all(a.fe is b.fe for a, b in zip(nominal.bodies[1:], twisted.bodies[1:], strict=True))


def test_a_mesh_file_rewritten_under_the_same_name_is_read_again(tmp_path):
    """The key holds the file's content, not its name: the bar scaled by 2 is a new FE model with twice the
    coordinates; the unchanged file is a hit."""
    write_bar(tmp_path)
    description = tomllib.loads(PENDULUM)
    cache = SceneCache()
    before = build_scene(description, tmp_path, cache=cache)
    assert build_scene(description, tmp_path, cache=cache).bodies[0].fe is before.bodies[0].fe
    mesh = meshio.read(tmp_path / "bar.vtu")
    meshio.write(tmp_path / "bar.vtu", meshio.Mesh(2.0 * mesh.points, mesh.cells))
    after = build_scene(description, tmp_path, cache=cache)
    np.testing.assert_array_equal(after.bodies[0].fe.nodes, 2.0 * before.bodies[0].fe.nodes)
    assert cache.stats()["fe_models"] == {"hits": 1, "disk_hits": 0, "misses": 2, "entries": 2}


def test_the_path_sensors_equal_those_of_a_whole_evaluation():
    """``sensors="path"`` (a study's row) evaluates the coupler's path and the drive only: the same values as
    every sensor's evaluation, and the same summary of them."""
    scene = build_bennett_from_options(_options(0.5))
    whole = load(scene).run(mode="quasi_static", outputs=9)
    path = load(scene).run(mode="quasi_static", outputs=9, sensors="path")
    assert sorted(path.sensors) == sorted(PATH_SENSORS)
    for name in PATH_SENSORS:
        np.testing.assert_array_equal(path.sensors[name], whole.sensors[name], err_msg=name)
    assert path.summary() == {name: whole.summary()[name] for name in path.summary()}
    assert len(path.summary()) == 3 and "energy_balance_relative" in whole.summary()


def test_the_ideal_coupler_path_is_traced_once_per_loop_and_equals_a_fresh_trace():
    """Every variant of a study shares the nominal loop, so the rigid path it is compared with (traced by
    continuation for a linkage that has no motion polynomial) comes from the cache after the first variant."""
    loop = SingleLoop(BennettLinkage.paper().axes)
    cache = SceneCache()
    first = build_linkage(loop, _options(0.3), cache=cache)
    second = build_linkage(loop, _options(-0.2), cache=cache)
    fresh = build_linkage(loop, _options(-0.2), cache=SceneCache(enabled=False))
    angles = second.drive_angle(0.0) + np.linspace(0.0, 1.0, 7)
    for scene in (first, second):
        scene.ideal_coupler_points(angles)
        scene.ideal_coupler_curve(36)
    assert cache.stats()["rigid_motions"]["hits"] == 2 + 2  # start pose and range, then points and curve
    np.testing.assert_array_equal(second.ideal_coupler_points(angles), fresh.ideal_coupler_points(angles))
    np.testing.assert_array_equal(second.ideal_coupler_curve(36), fresh.ideal_coupler_curve(36))
    kept = second.ideal_coupler_curve(36)
    kept[:] = 0.0  # a caller's changes stay its own
    assert np.any(second.ideal_coupler_curve(36) != 0.0)
