"""Stress state of the assembled Bennett linkage (ffrf.output.assembly_stress) against independent truth:
a full scikit-fem static solve of each link with the bores moved as the reduced solution's bore
markers say (Dirichlet conditions), the weight of the linkage carried by the clamp, and the
strain energy of the reduced stiffness. Coarse scenes (6 mm tetrahedra, 2 modes)."""

import json

import meshio
import numpy as np
import pytest
import skfem
from scipy.spatial.transform import Rotation

from ffrf import load
from ffrf.body.euler_parameters import rotation_matrix
from ffrf.fe.fe_model import FEModel
from ffrf.output.assembly_stress import (
    element_von_mises,
    joint_reactions,
    nearest_feature,
    nodal_average,
    scene_assembly_stress,
    write_assembly_vtu,
)
from ffrf.paper.bennett_scene import assemble, build_bennett

#: The links centred on the joint points (``collision_free=False``), where the tolerances below were measured.
COARSE = dict(h=6e-3, order=1, n_modes=2, collision_free=False)


def full_static_displacement(link, block: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """Full FE solution K u = f of one link, each bore (and the mount) moved rigidly as its marker.

    The bore's motion comes from the marker's world pose at the assembled coordinates:
    translation t = A^T (r_M - R) - x_bar and rotation vector theta = log(A^T A_M), imposed on the
    interface nodes as u_j = t + theta x (x_j - x_bar) (the rigid map of Eq. (HCB-2)); f is the
    gravity load M (A^T g) in the body frame."""
    fe = link.fe
    position, rotation = block[:3], rotation_matrix(block[3:7])
    u = np.zeros(fe.n_dofs)
    fixed = []
    for name, interface in link.interfaces.items():
        marker = link.markers[name]
        centre = interface.weighted_center(fe.nodes)
        t = rotation.T @ (marker.position(block) - position) - centre
        theta = Rotation.from_matrix(rotation.T @ marker.orientation(block)).as_rotvec()
        u[interface.dofs] = (t + np.cross(theta, fe.nodes[interface.nodes] - centre)).ravel()
        fixed.append(interface.dofs)
    load = fe.mass @ np.tile(rotation.T @ gravity, len(fe.nodes))
    return skfem.solve(*skfem.condense(fe.stiffness, load, x=u, D=np.concatenate(fixed))).reshape(-1, 3)


def stress_errors(variant: str, gravity) -> list[float]:
    """Largest |von Mises (reduced) - von Mises (full)| over the link's elements / max full, per link.
    Both go through ``element_von_mises``, itself checked against hand formulas in
    ``tests/test_fe_models/test_stress_recovery.py``: this compares the displacement fields."""
    scene = build_bennett(variant, gravity=gravity, **COARSE)
    solution = assemble(scene)
    stress = scene_assembly_stress(scene, solution.q, solution.multipliers)
    errors = []
    for link, reduced in zip(scene.links, stress.links, strict=True):
        assert isinstance(link.fe, FEModel)  # the Bennett's links are meshed by gmsh, not read from another program
        full = full_static_displacement(link, solution.q[scene.system.block(link.index)], np.asarray(gravity, float))
        truth = element_von_mises(link.fe.nodes, link.fe.mesh.tets, full, link.fe.material.E, link.fe.material.nu)
        errors.append(float(np.abs(reduced.element_von_mises - truth).max() / truth.max()))
    return errors


def test_misalignment_stress_equals_the_full_solve():
    """Without body loads Craig-Bampton reproduces interface-driven static fields exactly (the static
    modes are the exact condensation, Eq. (HCB-3)); measured 1.3e-12 relative on every link of pla1."""
    errors = stress_errors("pla1", (0.0, 0.0, 0.0))
    assert max(errors) < 1e-9, errors


def test_gravity_stress_is_close_to_the_full_solve():
    """Gravity loads the interior, which 2 fixed-interface modes capture only approximately:
    measured 0.2 % (base) to 3.6 % (coupler) of the largest stress; 0.8 % with 8 modes."""
    errors = stress_errors("pla", (0.0, 0.0, -9.81))
    assert max(errors) < 0.05, errors
    assert max(errors) > 1e-6  # not exact: the check above is not vacuous


@pytest.fixture(scope="module")
def assembled_pla1():
    scene = build_bennett("pla1", **COARSE)
    solution = assemble(scene)
    return scene, solution, scene_assembly_stress(scene, solution.q, solution.multipliers)


def test_strain_energy_and_clamp_reaction(assembled_pla1):
    scene, solution, stress = assembled_pla1
    for link, result in zip(scene.links, stress.links, strict=True):
        zeta = solution.q[scene.system.block(link.index)][7:]
        # Element sum of eps:sigma V / 2 against zeta^T K_red zeta / 2 (P1: the same quadratic form).
        assert result.strain_energy_j == pytest.approx(0.5 * zeta @ link.reduction.reduced_stiffness @ zeta, rel=1e-9)
    # Misalignment forces are self-equilibrated: the clamp carries exactly the weight of the four links.
    weight = 9.81 * sum(link.fe.total_mass for link in scene.links)
    clamp = stress.links[0].reactions["clamp"]
    assert clamp["force_n"] == pytest.approx(weight, rel=1e-8)
    # The most stressed element is close to a bore (the misalignment bends the links at their joints).
    assert all(r.nearest_feature.startswith("joint") and r.feature_distance_m < 0.012 for r in stress.links)
    assert stress.as_dict()["max_von_mises_pa"] > 5e5  # 1 deg misalignment: about 1.6 MPa


def test_assembly_vtu(assembled_pla1, tmp_path):
    scene, solution, stress = assembled_pla1
    path = write_assembly_vtu(tmp_path / "assembly.vtu", scene, stress)
    mesh = meshio.read(path)
    n_points = sum(len(link.fe.mesh.points) for link in scene.links)
    assert mesh.points.shape == (n_points, 3)
    cell_vm = mesh.cell_data["von_mises"][0]
    assert np.array_equal(cell_vm, np.concatenate([r.element_von_mises for r in stress.links]))
    point_vm = mesh.point_data["von_mises"]
    assert 0.0 < point_vm.max() <= cell_vm.max()  # averages never exceed the largest element value
    # Reference + displacement = current positions of the links (Warp By Vector).
    reference = np.vstack([link.fe.nodes[: len(link.fe.mesh.points)] for link in scene.links])
    assert np.allclose(reference + mesh.point_data["displacement"], mesh.points, atol=1e-15)


def test_pure_helpers():
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    assert np.allclose(nodal_average(5, tets, [2.0, 2.0], [1.0, 3.0]), 2.0)
    assert np.allclose(nodal_average(5, tets, [1.0, 3.0], [1.0, 3.0])[[0, 1, 4]], [1.0, 2.5, 3.0])
    name, distance = nearest_feature([0.0, 0.0, 1.0], {"a": [[0.0, 0.0, 0.0]], "b": [[0.0, 0.0, 3.0], [0, 2.0, 1.0]]})
    assert (name, distance) == ("a", 1.0)
    reactions = joint_reactions(["fixed", "drive"], [6, 6], [False, True], [3, 4, 0, 0, 0, 1, 0, 0, 0, 3, 4, -7])
    assert reactions == {
        "fixed": {"force_n": 5.0, "moment_nm": 1.0},
        "drive": {"force_n": 0.0, "moment_nm": 5.0, "torque_nm": -7.0},
    }


def test_run_linkage_reports_the_assembly():
    result = load(build_bennett("pla", **COARSE)).run(mode="quasi_static", outputs=3, t_end=0.5)
    report = json.loads(json.dumps(result.metadata["assembly"]))
    assert [link["link"] for link in report["links"]] == [0, 1, 2, 3]
    assert report["max_von_mises_pa"] == max(link["max_von_mises_pa"] for link in report["links"]) > 0
    # The quasi-static run starts at the assembled state (same equilibrium at t = 0).
    assert np.abs(result.q[0] - result.assembly.q).max() < 1e-9
