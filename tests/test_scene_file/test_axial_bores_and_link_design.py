"""DH offset errors (a bore's seat moved along its own axis, ``BoreError.axial``) and the links' dimensions
(``LinkageOptions.design``, scene files' ``parametric.design``, linkage files' ``link_design``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ffrf.geometry.link_geometry import LinkDesign
from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
from ffrf.scenes.assembly import assemble
from ffrf.scenes.linkage_description import BoreError, LinkageOptions, linkage_description
from kinematics.rational_mechanism import load_model, loop_from_mechanism

#: Coarse links (12 mm linear tetrahedra, 2 modes) and no gravity: the strain energy is the misfit's alone.
COARSE = {"h": 0.012, "order": 1, "n_modes": 2, "gravity": (0.0, 0.0, 0.0), "bore_error_model": "misfit"}


def test_an_axial_bore_error_moves_the_seat_along_the_bore_and_keeps_its_line():
    """The bore of joint 1 on link 1 (its second axis) shifted 0.3 mm along itself: same line, seat moved by
    0.3 mm along the axis direction; the link's other bore untouched."""
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    nominal = linkage_description(loop)["bodies"][1]["parametric"]["axes"]
    options = LinkageOptions(bore_errors=(BoreError(joint=1, link=1, axial=3e-4),))
    built = linkage_description(loop, options)["bodies"][1]["parametric"]["axes"]
    direction = np.asarray(nominal[1]["direction"])
    direction /= np.linalg.norm(direction)
    assert np.allclose(built[1]["direction"], nominal[1]["direction"], atol=1e-15)
    moved = np.subtract(built[1]["point"], nominal[1]["point"])
    assert np.linalg.norm(moved - (moved @ direction) * direction) < 1e-15  # still on the same line
    assert np.allclose(np.subtract(built[1]["joint_point"], nominal[1]["joint_point"]), 3e-4 * direction, atol=1e-15)
    assert built[0] == nominal[0]


def test_a_tilted_or_shifted_bore_turns_about_or_moves_along_the_binormal_through_its_joint_point():
    """The bore of joint 1 on link 1 tilted by 0.5 deg: its axis turns by 0.5 deg towards the link's common normal
    (about the binormal, the axis crossed with the normal) and its joint point stays; shifted by 0.2 mm: the same
    direction, the joint point and the seat moved by 0.2 mm along the binormal, which is square to the axis and the
    normal. The link's other bore is untouched either way; with both zero the side is the nominal one (1e-15 m)."""
    from kinematics.pluecker import common_normal

    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    nominal = linkage_description(loop)["bodies"][1]["parametric"]["axes"]
    other, own = (np.asarray(nominal[k]["direction"], dtype=float) for k in (0, 1))
    own /= np.linalg.norm(own)
    normal = common_normal(loop.axes[0], loop.axes[1]).unit
    binormal = np.cross(own, normal)
    tilted = LinkageOptions(bore_errors=(BoreError(joint=1, link=1, tilt=np.radians(0.5)),))
    built = linkage_description(loop, tilted)["bodies"][1]["parametric"]["axes"]
    turned = np.asarray(built[1]["direction"], dtype=float)
    turned /= np.linalg.norm(turned)
    assert abs(np.arccos(np.clip(turned @ own, -1, 1)) - np.radians(0.5)) < 1e-12
    assert abs(turned @ binormal) < 1e-15  # turned about the binormal: towards the normal
    assert abs(abs(turned @ normal) - np.sin(np.radians(0.5))) < 1e-12
    assert np.allclose(built[1]["joint_point"], nominal[1]["joint_point"], atol=1e-15)
    assert built[0] == nominal[0]
    shifted = LinkageOptions(bore_errors=(BoreError(joint=1, link=1, shift=2e-4),))
    built = linkage_description(loop, shifted)["bodies"][1]["parametric"]["axes"]
    assert np.allclose(built[1]["direction"], nominal[1]["direction"], atol=1e-15)
    for key in ("joint_point", "point"):
        moved = np.subtract(built[1][key], nominal[1][key])
        assert np.allclose(moved, 2e-4 * binormal, atol=1e-15), key
    assert abs(binormal @ other) > 0.1  # not a move the DH offset of the other axis would be
    assert built[0] == nominal[0]
    none = LinkageOptions(bore_errors=(BoreError(joint=1, link=1, tilt=0.0, shift=0.0),))
    unchanged = linkage_description(loop, none)["bodies"][1]["parametric"]["axes"]
    for key in ("direction", "joint_point", "point"):
        assert np.allclose(unchanged[1][key], nominal[1][key], rtol=0, atol=1e-15), key


def _assembly_strain_energy(options: LinkageOptions) -> float:
    scene = build_bennett_from_options(options)
    q = assemble(scene).q
    return scene.system.energies(q, np.zeros_like(q))["strain"]


def test_a_dh_offset_error_breaks_bennetts_condition_with_a_misfit_energy_quadratic_in_it():
    """Bennett's linkage needs d = 0 at every joint; the base's bore of joint 3 moved 0.05 and 0.1 mm along its
    axis leaves a misfit the links close elastically: linear elasticity makes the energy quadratic in the error
    (ratio 4 for twice the error), and it vanishes without the error."""
    base = replace(bennett_options("pla"), **COARSE)
    energies = [
        _assembly_strain_energy(replace(base, bore_errors=(BoreError(joint=3, link=0, axial=e),)) if e else base)
        for e in (0.0, 5e-5, 1e-4)
    ]
    assert energies[0] < 1e-12 * energies[2]
    assert energies[1] > 1e-7  # the error is felt: 0.1 mm of misfit in 16 mm PLA links
    assert abs(energies[2] / energies[1] - 4.0) < 0.02, energies


def test_thicker_arms_are_built_and_make_the_same_misfit_cost_more_energy():
    """The links' arm thickness reaches the meshes (each link's geometry carries the design), and a stiffer section
    stores more energy for the same bore misfit (0.5 deg twist of the base's bore of joint 3)."""
    twisted = replace(
        bennett_options("pla"), **COARSE, bore_errors=(BoreError(joint=3, link=0, twist=np.radians(0.5)),)
    )
    thick = replace(twisted, design=LinkDesign(arm_thickness=18e-3))
    scene = build_bennett_from_options(thick)
    assert all(body.geometry is not None and body.geometry.design == thick.design for body in scene.bodies)
    assert _assembly_strain_energy(thick) > 1.2 * _assembly_strain_energy(twisted)
