"""Scene bodies from another program's M and K (``matrices = {...}``) and with free-free modes
(``reduction = "free_free"``), each against a truth computed another way.

* The bar pendulum of ``scene_fixtures`` from its M and K written to files runs as from its mesh (the same
  physics by another input route: the same numbers to round-off).
* A free-free scene body has the free-free frequencies of the full FE model (dense LAPACK, not our
  Lanczos), and tumbling freely it keeps its angular momentum (summed node by node with the full M).
* Exudyn's ``abaqusImportTest`` (five Abaqus blocks, clamped, sagging) written as one scene file reproduces
  the value Exudyn's test suite stores.
"""

import tomllib

import numpy as np
import pytest
import scipy.io
import scipy.linalg
from body_fixtures import bar_model
from scene_fixtures import PENDULUM, write_bar

from ffrf import load
from ffrf.body.euler_parameters import g_bar, rotation_matrix
from ffrf.errors import InterfaceError
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.matrix_import import write_npz_model
from ffrf.output.sensors import node_sensors
from ffrf.scenes.builder import build_scene
from ffrf.scenes.scene_file import load_scene
from validation.testmodels import model_named
from validation.testmodels.fe_data import BLOCKS, DATA
from validation.testmodels.spec import STORED_TOLERANCE

MESH_BODY = 'mesh = "bar.vtu"\nunit = "mm"\nmaterial = {E = 1e8, nu = 0.3, rho = 450.0}\norder = 1\n'


def _write_matrices(directory, fe) -> None:
    """The bar's nodes and matrices as a .npz with its tetrahedra, and as Matrix Market files with a node table."""
    write_npz_model(directory / "bar.npz", ExternalFEModel(fe.nodes, fe.mass, fe.stiffness, {"Tet4": fe.mesh.tets}))
    scipy.io.mmwrite(directory / "M.mtx", fe.mass)
    scipy.io.mmwrite(directory / "K.mtx", fe.stiffness)
    np.savetxt(directory / "nodes.txt", fe.nodes, fmt="%.17g")


ROUTES = {
    # route: (matrices table, interface weights of both runs)
    "npz with elements": ('{format = "npz", file = "bar.npz"}', "area"),
    "Matrix Market and a node table": (
        '{format = "matrix_market", nodes = "nodes.txt", mass = "M.mtx", stiffness = "K.mtx"}',
        "equal",
    ),
}


@pytest.mark.parametrize("route", ROUTES)
def test_a_body_from_its_matrices_runs_as_from_its_mesh(tmp_path, route):
    """Same bar, same interface rule, M and K by file: the pendulum swings the same to round-off (measured: npz
    0 (equal bits), Matrix Market 0 on the tip's path)."""
    table, weights = ROUTES[route]
    write_bar(tmp_path)
    pendulum = PENDULUM.replace("t_end = 0.1", "t_end = 0.03").replace(
        'nodes_file = "hinge.txt"}', f'nodes_file = "hinge.txt", weights = "{weights}"}}'
    )
    (tmp_path / "mesh.toml").write_text(pendulum)
    from_mesh = load_scene(tmp_path / "mesh.toml")
    _write_matrices(tmp_path, from_mesh.bodies[0].fe)
    (tmp_path / "matrices.toml").write_text(pendulum.replace(MESH_BODY, f"matrices = {table}\n"))
    from_matrices = load_scene(tmp_path / "matrices.toml")
    ours, theirs = load(from_mesh).run(), load(from_matrices).run()
    travel = np.abs(ours.q - ours.q[0]).max()  # the pendulum swings: its largest change of a coordinate
    assert travel > 1e-2
    np.testing.assert_allclose(theirs.q, ours.q, rtol=0, atol=1e-12 * travel)


def test_a_body_from_matrices_reports_strain_energy_and_no_stress(tmp_path):
    """The static start of a body from matrices (the bar clamped at its hinge face): its strain energy 1/2 u^T K u
    is reported, its stress is None, and assembly.vtu is not written (no elements of ours) instead of failing
    inside the stress recovery."""
    model = write_bar(tmp_path)
    _write_matrices(tmp_path, model)
    text = PENDULUM.replace(MESH_BODY, 'matrices = {format = "npz", file = "bar.npz"}\n')
    text = text.replace('mode = "dynamic"', 'mode = "quasi_static"').replace('type = "revolute"', 'type = "fixed"')
    (tmp_path / "scene.toml").write_text(text.replace("outputs = 101", "outputs = 2"))
    result = load(tmp_path / "scene.toml").run()
    result.save(tmp_path / "out")
    metadata = result.metadata
    body = metadata["assembly"]["links"][0]
    assert body["max_von_mises_pa"] is None and metadata["assembly"]["max_von_mises_pa"] is None
    assert body["strain_energy_j"] > 0.0
    assert not (tmp_path / "out" / "assembly.vtu").exists()


def test_matrices_without_elements_need_interface_weights(tmp_path):
    model = write_bar(tmp_path)
    _write_matrices(tmp_path, model)
    table = ROUTES["Matrix Market and a node table"][0]
    (tmp_path / "scene.toml").write_text(PENDULUM.replace(MESH_BODY, f"matrices = {table}\n"))
    with pytest.raises(InterfaceError, match='no elements, so its nodes span no surface area; add weights = "equal"'):
        load_scene(tmp_path / "scene.toml")


def _free_bar(model, modes: int) -> dict:
    """A scene description of the bar as a free-free body from its matrices (no joints, no gravity)."""
    return {
        "scene": {"gravity": [0.0, 0.0, 0.0], "rho_inf": 1.0, "t_end": 0.02, "step": 1e-4, "outputs": 21},
        "bodies": [
            {
                "name": "bar",
                "matrices": {"format": "npz", "file": "bar.npz"},
                "reduction": "free_free",
                "modes": modes,
                "interfaces": [{"name": "end", "plane": {"point": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]}}],
                "velocity": {"linear": [0.1, 0.0, 0.0], "angular": [0.5, 1.0, 5.0]},
            }
        ],
    }


def test_free_free_body_has_the_free_free_frequencies_of_the_fe_model(tmp_path):
    """``modes`` counts the elastic modes; their frequencies are the 7th.. eigenvalues of the full (K, M), solved
    dense by LAPACK (measured: 3.3e-12 relative; 382, 440, 1009, 1113 Hz)."""
    model = bar_model(E=1e8, rho=450.0)
    _write_matrices(tmp_path, model)
    scene = build_scene(_free_bar(model, 4), tmp_path)
    body = scene.bodies[0]
    reduced = scipy.linalg.eigh(body.reduction.reduced_stiffness, body.reduction.reduced_mass, eigvals_only=True)
    full = scipy.linalg.eigh(model.stiffness.toarray(), model.mass.toarray(), eigvals_only=True)
    assert body.reduction.n_modes == 4
    np.testing.assert_allclose(reduced, full[6:10], rtol=1e-10)


def _angular_momentum(model, basis, q, qd):
    """World angular momentum about the origin: sum over nodes of x_i x (M v)_i (examples/ex03)."""
    a, omega = rotation_matrix(q[3:7]), g_bar(q[3:7]) @ qd[3:7]
    u = model.nodes + (basis @ q[7:]).reshape(-1, 3)
    velocities = qd[:3] + (np.cross(omega, u) + (basis @ qd[7:]).reshape(-1, 3)) @ a.T
    momenta = (model.mass @ velocities.reshape(-1)).reshape(-1, 3)
    return np.cross(q[:3] + u @ a.T, momenta).sum(axis=0)


def test_free_free_body_tumbling_freely_keeps_its_angular_momentum(tmp_path):
    """Nothing acts on the spinning bar: its angular momentum stays (generalized-alpha, rho_inf = 1; measured
    drift 3.4e-10 relative over 0.02 s, the integrator's error)."""
    model = bar_model(E=1e8, rho=450.0)
    _write_matrices(tmp_path, model)
    scene = build_scene(_free_bar(model, 4), tmp_path)
    run = load(scene).run()
    basis = scene.bodies[0].reduction.basis
    momentum = np.array([_angular_momentum(model, basis, q, qd) for q, qd in zip(run.q, run.qd, strict=True)])
    assert np.linalg.norm(momentum[0]) > 0.0
    assert np.abs(momentum - momentum[0]).max() < 1e-6 * np.linalg.norm(momentum[0])


def _abaqus_scene(data) -> str:
    """``abaqusImportTest.py`` as a scene file: five blocks (one per Abaqus element type), each clamped at its face
    x = 0 (area weights, 5 Craig-Bampton modes), Exudyn's gravity model, no damping; sensors at (4, 0, 0)."""
    text = """
[scene]
gravity = [0.0, -9.81, 0.0]
exact_gravity = false
t_end = 5e-3
step = 1e-4
rho_inf = 0.5
outputs = 51
"""
    for element in BLOCKS:
        stem = data / "abaqus" / f"block{element}"
        text += f"""
[[bodies]]
name = "{element}"
modes = 5
interfaces = [{{name = "face", plane = {{point = [0.0, 0.0, 0.0], normal = [-1.0, 0.0, 0.0]}}}}]
[bodies.matrices]
format = "abaqus"
nodes = "{stem}.inp"
instance = "block-1"
mass = "{stem}_MASS1.mtx.xz"
stiffness = "{stem}_STIF1.mtx.xz"
[[joints]]
name = "clamp {element}"
type = "fixed"
body0 = "ground"
body1 = "{element}"
interface1 = "face"
point = [0.0, 0.5, 0.5]
[[sensors]]
name = "tip {element}"
body = "{element}"
point = [4.0, 0.0, 0.0]
"""
    return text


def test_abaqus_blocks_as_a_scene_file_reproduce_exudyns_stored_value(tmp_path):
    """The sum over the five blocks of |displacement| of the node at (4, 0, 0) at 5 ms is the number Exudyn's test
    suite stores for ``abaqusImportTest`` (``runTestSuiteRefSol.py``), within the tolerance ``python -m validation
    testmodels`` judges it by (measured: 6.8e-13 relative)."""
    (tmp_path / "blocks.toml").write_text(_abaqus_scene(DATA))
    scene = load_scene(tmp_path / "blocks.toml")
    run = load(scene).run()
    assert run.time[-1] == pytest.approx(5e-3)
    positions = node_sensors(scene, run.q[-1:])
    result = 0.0
    for name, (k, node) in scene.sensors.items():  # the clamped frame stays put: world displacement = local
        reference = scene.bodies[k].fe.nodes[node]
        assert np.linalg.norm(reference - [4.0, 0.0, 0.0]) < 1e-12, name
        result += float(np.abs(positions[name][0] - reference).sum())
    assert result == pytest.approx(model_named("abaqusImportTest").stored.value, rel=STORED_TOLERANCE)


def test_a_plane_selects_the_face_a_node_list_selects(tmp_path):
    """``plane = {point, normal}`` on a mesh body: the nodes of the face x = 0 with the area weights the same face
    gets from its node list (``write_bar`` lists the nodes with x = 0), and ``weights = "equal"`` makes them 1/n."""
    write_bar(tmp_path)
    plane = "plane = {point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0]}"
    listed, by_plane, equal = (
        build_scene(tomllib.loads(PENDULUM.replace('nodes_file = "hinge.txt"', selector)), tmp_path)
        .bodies[0]
        .interfaces["hinge"]
        for selector in ('nodes_file = "hinge.txt"', plane, plane + ', weights = "equal"')
    )
    np.testing.assert_array_equal(by_plane.nodes, listed.nodes)
    np.testing.assert_allclose(by_plane.weights, listed.weights, rtol=0, atol=1e-15)
    np.testing.assert_allclose(equal.weights, 1.0 / len(listed.nodes), rtol=0, atol=1e-15)
