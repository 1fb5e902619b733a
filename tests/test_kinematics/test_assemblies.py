"""Assemblies off a loop's motion (kinematics.assemblies) against independent truth.

- the Bennett linkage's closed-form configuration curve (kinematics.bennett): every closing pose, from
  starts anywhere on the torus, lies on it (its configuration set is that one curve);
- the planar four-bar's two assembly modes (circle intersection): the mirrored mode is another branch;
- for a 6R of Rational Linkages: the loop product of dual quaternions (not the solver's residual) at each
  isolated assembly, the rank of its Jacobian, and Rational Linkages' own motion at the same drive angle;
- the same seed gives the same assemblies.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from kinematics_reference import random_bennett

from kinematics import BennettLinkage, SingleLoop, follow_driver, trace_motion, wrap_angle
from kinematics.__main__ import main
from kinematics.assemblies import nearby_assemblies, solve_closure
from kinematics.dual_quaternion import DualQuaternion
from kinematics.rational_mechanism import factor_joint_angles, load_model, loop_from_mechanism, regular_start


@pytest.fixture(scope="module")
def collisions_free():
    """collisions_free_6r (scale 0.1), its motion and the assemblies found from 30 starts (measured: 2 isolated)."""
    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, scale=0.1)
    motion = trace_motion(loop, driver=0, n_poses=96, start=regular_start(mechanism, loop))
    return mechanism, motion, nearby_assemblies(motion, starts=30, spread=1.5, seed=0)


def _loop_product(loop: SingleLoop, phi: np.ndarray) -> DualQuaternion:
    r"""(L2) in dual quaternions: :math:`\prod_i (\cos\frac{\varphi_i}2 + \sin\frac{\varphi_i}2 h_i)`."""
    product, one = DualQuaternion.identity(), DualQuaternion.identity()
    for axis, angle in zip(loop.axes, phi, strict=True):
        product = product * (one * np.cos(angle / 2) + axis.to_dual_quaternion() * np.sin(angle / 2))
    return product


def test_bennett_closure_has_only_its_motion(rng):
    """Bennett's configuration curve t_i = k_i t is the whole real configuration set: from starts drawn
    uniformly over the torus, every closing pose equals the closed form at its own drive angle (measured
    8e-15 rad at most), and the search reports nothing off the motion."""
    for a, alpha in [(BennettLinkage.paper().a, BennettLinkage.paper().alpha), random_bennett(rng)]:
        bennett = BennettLinkage(a, alpha)
        loop = SingleLoop(bennett.axes)
        for start in rng.uniform(-np.pi, np.pi, (15, 4)):
            phi = solve_closure(loop, start)
            assert phi is not None
            theta = bennett.joint_angles_from_driver(bennett.home_theta[3] + phi[3], joint=3)
            assert np.max(np.abs(wrap_angle(theta - bennett.home_theta - phi))) < 1e-12
        motion = trace_motion(loop, driver=3, n_poses=48)
        result = nearby_assemblies(motion, starts=10, spread=3.0, seed=1)
        assert result.assemblies == () and result.on_motion == result.converged == 10


def test_planar_four_bar_other_assembly_mode_is_a_branch():
    """A Grashof crank-rocker has two assembly modes, mirror images about the line from the crank pin to
    the rocker's pivot (two circle intersections); the one not traced is a mobile branch, not isolated."""
    ground, crank, coupler, rocker = 0.4, 0.1, 0.35, 0.3
    joints = np.array([[0, 0, 0], [crank * 0.5, crank * np.sqrt(0.75), 0], [0, 0, 0], [ground, 0, 0]], dtype=float)
    pin, pivot = joints[1, :2], joints[3, :2]
    distance = np.linalg.norm(pivot - pin)
    along = (coupler**2 - rocker**2 + distance**2) / (2 * distance)
    unit = (pivot - pin) / distance
    joints[2, :2] = pin + along * unit + np.sqrt(coupler**2 - along**2) * np.array([-unit[1], unit[0]])
    loop = SingleLoop.from_points_directions(joints, np.tile([0.0, 0.0, 1.0], (4, 1)))
    motion = trace_motion(loop, driver=0, n_poses=48)
    result = nearby_assemblies(motion, starts=12, spread=2.0, seed=0)
    assert result.isolated == () and len(result.of_kind("branch")) > 0
    for branch in result.of_kind("branch"):
        transforms = loop.link_transforms(branch.phi)
        pin = (transforms[1] @ [*joints[1], 1.0])[:2]  # crank pin, on link 1
        elbow = (transforms[2] @ [*joints[2], 1.0])[:2]  # coupler-rocker joint, on link 2
        traced = (follow_driver(loop, 0, [branch.phi[0]]).link_transforms()[0, 2] @ [*joints[2], 1.0])[:2]
        unit = (pivot - pin) / np.linalg.norm(pivot - pin)
        mirrored = traced - 2.0 * ((traced - pin) @ [-unit[1], unit[0]]) * np.array([-unit[1], unit[0]])
        assert np.max(np.abs(elbow - mirrored)) < 1e-12


def test_isolated_assemblies_of_a_6r_close_are_rigid_and_off_the_motion(collisions_free):
    """Each isolated assembly of collisions_free_6r: the dual-quaternion loop product is +-1 to 1e-12, the
    closure Jacobian has full rank (smallest singular value 1.9e-2 and 3.3e-2 of the largest, measured), and
    Rational Linkages' motion at the same drive angle is elsewhere (1.1 and 1.3 rad RMS, measured)."""
    mechanism, motion, result = collisions_free
    assert len(result.isolated) >= 1
    first = mechanism.factorizations[0]
    for assembly in result.isolated:
        product = _loop_product(motion.loop, assembly.phi).coeffs
        product = product * np.sign(product[0])
        assert np.max(np.abs(product - np.eye(8)[0])) < 1e-12
        assert np.linalg.svd(motion.loop.jacobian(assembly.phi), compute_uv=False)[-1] > 1e-6
        t = first.joint_angle_to_t_param(float(np.mod(-assembly.phi[0], 2.0 * np.pi)))  # Rational Linkages' map
        assert np.max(np.abs(wrap_angle(factor_joint_angles(mechanism, t) - assembly.phi))) > 0.1
        assert assembly.distance_rms > 0.1 and assembly.gap_translation > 1e-3  # and nearest pose's misfit is mm


def test_same_seed_same_assemblies(collisions_free):
    _, motion, result = collisions_free
    again = nearby_assemblies(motion, starts=30, spread=1.5, seed=0)
    assert [a.as_dict() for a in again.assemblies] == [a.as_dict() for a in result.assemblies]
    assert (again.converged, again.on_motion) == (result.converged, result.on_motion)


def test_nearby_command_prints_the_table_and_writes_json(tmp_path, capsys):
    out = tmp_path / "nearby.json"
    args = ["nearby", "--model", "collisions_free_6r", "--starts", "8", "--spread", "1.5", "--poses", "48"]
    assert main([*args, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "collisions_free_6r (scale 0.1): 8 starts" in text
    summary = json.loads(out.read_text())
    assert summary["starts"] == 8 and summary["model"] == "collisions_free_6r"
    assert all(len(a["phi_rad"]) == 6 for a in summary["assemblies"])
    assert main(["nearby", "--model", "collisions_free_6r", "--starts", "0"]) == 2
    assert main(["nearby", "--model", "collisions_free_6r", "--spread", "nan"]) == 2
    assert capsys.readouterr().err.count("error: ") == 2
