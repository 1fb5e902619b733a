"""Exact derivatives by the links' section (Eqs. (D1), (D5), issue #35): the design velocity against the CAD's own
volumes, and the path's derivatives against re-solved linkages on morphed meshes and on remeshed links."""

from dataclasses import replace

import numpy as np
import pytest

from ffrf.errors import GeometryError
from ffrf.fe.materials import PLA
from ffrf.geometry.design_velocity import SECTION_PARAMETERS, design_velocity
from ffrf.geometry.link_geometry import LinkDesign, build_link
from ffrf.geometry.meshing import gmsh_session
from ffrf.mesh.tet_mesh import TetMesh
from ffrf.output.clearance import signed_clearance
from ffrf.output.peak_stress import corner_stress, stress_norm_at
from ffrf.output.sensors import path_sensors
from ffrf.output.solid_distance import LinkSolid
from ffrf.output.stress_average import ball_average
from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
from ffrf.scenes.builder import morphed_body, parametric_link
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.path_sensitivity import section_sensitivity, section_velocities
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import static_equilibrium

ROWS = [1, 3, 4]


def _options(h: float = 8e-3, order: int = 1, n_modes: int = 2):
    return replace(bennett_options("pla", h=h, order=order, n_modes=n_modes), material=PLA)


@pytest.fixture(scope="module")
def bennett_path():
    scene = build_bennett_from_options(_options())
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    return scene, result


def _cad_volume(build: dict) -> float:
    with gmsh_session("volume") as gmsh:
        build_link(gmsh, **build)
        return sum(gmsh.model.occ.getMass(3, tag) for _, tag in gmsh.model.getEntities(3))


@pytest.mark.parametrize("parameter", SECTION_PARAMETERS)
def test_the_morph_changes_the_volume_as_the_cad_solid_does_and_leaves_the_bores(bennett_path, parameter):
    """Link 2 of the PLA Bennett: the volume of its mesh morphed along the design velocity changes as
    OpenCASCADE's exact volume of the solid built at the changed dimension, to the faceting of the curved faces
    (measured at h = 8 mm: 0.38 % for the arm's width, 0.34 % for its thickness, -3.2 % for the housing's radius,
    whose cylinder the facets cut inside; -0.9 % at h = 4 mm, the facets' second order); the bores' nodes (the
    joints' interfaces) do not move."""
    scene, _ = bennett_path
    spec = scene.description["bodies"][2]["parametric"]
    build = parametric_link(spec)
    mesh, velocity = design_velocity(build, float(spec["h"]), parameter)
    step = 1e-7
    morphed = [TetMesh(mesh.points + sign * step * velocity, mesh.tets).volume for sign in (1.0, -1.0)]
    ours = (morphed[0] - morphed[1]) / (2 * step)
    design, change = build["design"], 1e-6
    cad = [
        _cad_volume(dict(build, design=replace(design, **{parameter: getattr(design, parameter) + s})))
        for s in (change, -change)
    ]
    exact = (cad[0] - cad[1]) / (2 * change)
    assert exact > 1e-3  # m^3 per m: a real change of the solid
    assert abs(ours / exact - 1) < (0.04 if parameter == "housing_outer_radius" else 0.005)
    bores = np.concatenate([itf.nodes for itf in scene.bodies[2].interfaces.values()])
    np.testing.assert_allclose(velocity[bores], 0.0, atol=1e-9)


def test_a_dimension_that_is_no_section_is_refused(bennett_path):
    scene, _ = bennett_path
    spec = scene.description["bodies"][2]["parametric"]
    with pytest.raises(GeometryError, match="unknown"):
        design_velocity(parametric_link(spec), 8e-3, "arm_length")


@pytest.mark.parametrize(("link", "parameter"), [(2, "arm_thickness"), (1, "arm_width"), (3, "housing_outer_radius")])
def test_the_path_derivatives_agree_with_re_solved_linkages_on_the_morphed_mesh(bennett_path, link, parameter):
    """The derivatives of the coupler point and the driving torque by a link's section dimension (Eq. (D1) with the
    morph's rates) against central differences of equilibria re-solved by Newton for the linkage with that link
    rebuilt on its mesh morphed by +-1e-3 of the dimension (the same model, differentiated the long way), within
    1e-6 of the largest derivative (measured 2e-9 to 9e-9 for the coupler point). The lowest squared frequency of
    Eq. (B1) likewise, within 1e-5 of the largest derivative: the re-solved side's eigenvalue round-off over the steps
    sets it (link 1's arm width: 6.3e-5 at steps of 1e-4, 1.8e-5 at 3e-4, 7.3e-6 at 1e-3, where the coupler
    point's truncation is still 9e-9), and every link's peak von Mises stress (at the peak's
    corner; the morphed link's own stress field changes too), within 1e-6, and the p-norm of every link's corner
    stresses (Eq. (D10)) likewise."""
    scene, result = bennett_path
    exact = section_sensitivity(
        scene, result.time, result.q, result.multipliers, (parameter,), (link,), stability=True, stress=True
    )
    spec = scene.description["bodies"][link]["parametric"]
    build = parametric_link(spec)
    mesh, velocity = design_velocity(build, float(spec["h"]), parameter)
    step = 1e-3 * getattr(build["design"], parameter)

    def outputs(change: float) -> dict:
        moved = scene.with_body(morphed_body(scene, link, mesh.points + change * velocity))
        solved = []
        for r in ROWS:
            first = static_equilibrium(moved.system, result.q[r], t=float(result.time[r]), tolerance=1e-13)
            solved.append(static_equilibrium(moved.system, first.q, t=float(result.time[r]), tolerance=1e-15))
        q = np.array([s.q for s in solved])
        mu = [
            equilibrium_stability(moved.system, s.q, s.multipliers, float(result.time[r]), 1).squared_frequencies[0]
            for s, r in zip(solved, ROWS, strict=True)
        ]
        peaks = [
            [
                corner_stress(body.mesh_model, body.reduction.basis, s.q[moved.system.block(k)][7:], *corner)
                for k, (body, corner) in enumerate(zip(moved.bodies, exact.peak_stress_corner[r], strict=True))
            ]
            for s, r in zip(solved, ROWS, strict=True)
        ]
        norms = [
            [stress_norm_at(body.mesh_model, body.reduction.basis, s.q[moved.system.block(k)][7:])
             for k, body in enumerate(moved.bodies)]
            for s in solved
        ]  # fmt: skip
        return path_sensors(moved, result.time[ROWS], q, np.array([s.multipliers for s in solved])) | {
            "mu": mu,
            "peaks": peaks,
            "norms": norms,
        }

    near, far = ((outputs(s * step), outputs(-s * step)) for s in (1.0, 2.0))
    assert exact.lowest_squared_frequency is not None and exact.peak_stress_slopes is not None
    assert exact.stress_norm_slopes is not None
    for name, ours, tolerance in (
        ("coupler_point", exact.coupler_point[ROWS, :, 0], 1e-6),
        ("driving_torque", exact.driving_torque[ROWS, 0], 1e-6),
        ("mu", exact.lowest_squared_frequency[ROWS, 0], 1e-5),
        ("peaks", exact.peak_stress_slopes[ROWS, :, 0], 1e-6),
        ("norms", exact.stress_norm_slopes[ROWS, :, 0], 1e-6),
    ):
        central = [
            (np.asarray(plus[name]) - np.asarray(minus[name])) / (2 * s * step)
            for s, (plus, minus) in ((1, near), (2, far))
        ]
        theirs = (4 * central[0] - central[1]) / 3  # Richardson's rule: truncation step^4
        print(name, np.abs(np.asarray(ours) - theirs).max() / np.abs(theirs).max())
        assert np.abs(theirs).max() > 0.0
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=tolerance * np.abs(theirs).max())


def test_the_smallest_clearance_moves_as_the_morphed_links_clearance_over_the_whole_motion(bennett_path):
    """Eq. (CL5): each pair's smallest clearance along the revolution (24 poses and the bisections of Eq. (CL4)),
    differentiated at the pose that holds it, against central differences of the whole check re-run on the solids
    morphed by +-1e-4 of each dimension (the smallest found again, anywhere): within 1e-6 of the largest derivative
    (measured 1e-11 for the width, 5e-8 for the thickness). Where an arm's face holds a pair's clearance, a
    thicker arm closes the gap by half the change (its faces move by half of it either side of the mid-plane):
    -0.5, exactly."""
    scene, _ = bennett_path
    parameters = ("arm_width", "arm_thickness")
    velocities = section_velocities(scene, parameters)
    steps = np.array([1e-4 * getattr(LinkDesign(), p) for p in parameters])
    found = scene.clearance(n_poses=24)
    assert np.all(found.distance > 0.0)  # apart: the witness of a smallest clearance is a pose
    ours = scene.clearance_slopes(found, velocities, parameters, steps, n_poses=24)
    solids, zones, motion = scene.link_solids(), scene.joint_zones(), scene.rigid_revolution(24)
    for j, parameter in enumerate(parameters):
        sides = [
            signed_clearance(
                [LinkSolid(s.vertices + sign * steps[j] * velocities.get((k, parameter), 0.0 * s.vertices),
                           s.triangles, s.name) for k, s in enumerate(solids)],
                motion, zones,
            ).distance
            for sign in (1.0, -1.0)
        ]  # fmt: skip
        theirs = (sides[0] - sides[1]) / (2.0 * steps[j])
        print(parameter, "ours", ours[:, j], "error", np.abs(ours[:, j] - theirs).max() / np.abs(theirs).max())
        np.testing.assert_allclose(ours[:, j], theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())
    assert np.any(np.abs(ours[:, 1] + 0.5) < 1e-6)  # an arm's face half the thickness's change from its mid-plane


@pytest.mark.slow
def test_the_path_derivatives_agree_with_remeshed_linkages_to_the_discretisation():
    """Every link's arm thickness at once (the sum of the links' derivatives), quadratic links at h = 8 mm: central
    differences of linkages remeshed at +-0.5 mm agree with ours to 1 % of the largest (measured 0.14 % for the
    coupler, 0.35 % for the torque, 0.19 % for the mass): the morph's derivative is the remeshed model's up to the
    discretisation, which remeshing changes and no derivative can follow."""
    options = _options(8e-3, 2, 4)
    scene = build_bennett_from_options(options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    exact = section_sensitivity(scene, result.time, result.q, result.multipliers, ("arm_thickness",))
    coupler, torque = exact.coupler_point[ROWS].sum(axis=2), exact.driving_torque[ROWS].sum(axis=1)
    assert exact.mass is not None

    def remeshed(change: float) -> tuple[dict, float]:
        design = replace(options.design, arm_thickness=options.design.arm_thickness + change)
        built = build_bennett_from_options(replace(options, design=design))
        solved = [static_equilibrium(built.system, result.q[r], t=float(result.time[r])) for r in ROWS]
        q, lam = np.array([s.q for s in solved]), np.array([s.multipliers for s in solved])
        return path_sensors(built, result.time[ROWS], q, lam), sum(b.moments.mass for b in built.system.bodies)

    (plus, mass_plus), (minus, mass_minus) = remeshed(5e-4), remeshed(-5e-4)
    for name, ours in (("coupler_point", coupler), ("driving_torque", torque)):
        theirs = (plus[name] - minus[name]) / 1e-3
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-2 * np.abs(theirs).max())
    assert abs((mass_plus - mass_minus) / 1e-3 / exact.mass.sum() - 1) < 1e-2


def test_a_section_where_a_link_changes_its_topology_is_refused():
    """The PLA Bennett's link 1 with a 6 mm arm: its arm's edges at the housing vanish when the arm widens by a step,
    so no derivative exists there; the error names the dimension and the entity instead of returning a number."""
    options = _options(12e-3)
    scene = build_bennett_from_options(replace(options, design=replace(options.design, arm_width=6e-3)))
    with pytest.raises(GeometryError, match="changes the link's topology"):
        section_velocities(scene, ("arm_width",), (1,))


def test_the_averaged_stress_derivatives_agree_with_re_solved_linkages_on_the_morphed_mesh(bennett_path):
    """With a ``stress_radius`` (Eq. (D14)), by link 2's arm thickness: every link's largest stress averaged over
    4 mm balls (at its ball) and the p-norm of its averaged stresses agree with those of equilibria re-solved for the
    linkage with that link rebuilt on its mesh morphed by +-1e-3 and +-2e-3 of the dimension (Richardson), averaged
    over the nominal mesh's balls (the same elements, their moved volumes), within 1e-6 of the largest (measured
    2.5e-8 for both)."""
    scene, result = bennett_path
    link, parameter, radius = 2, "arm_thickness", 4e-3
    exact = section_sensitivity(
        scene, result.time, result.q, result.multipliers, (parameter,), (link,), stress=True, stress_radius=radius
    )
    averages = [ball_average(body.mesh_model, radius) for body in scene.bodies]
    spec = scene.description["bodies"][link]["parametric"]
    build = parametric_link(spec)
    mesh, velocity = design_velocity(build, float(spec["h"]), parameter)
    step = 1e-3 * getattr(build["design"], parameter)

    def outputs(change: float) -> tuple[np.ndarray, np.ndarray]:
        moved = scene.with_body(morphed_body(scene, link, mesh.points + change * velocity))
        peaks, norms = [], []
        for r in ROWS:
            first = static_equilibrium(moved.system, result.q[r], t=float(result.time[r]), tolerance=1e-13)
            q = static_equilibrium(moved.system, first.q, t=float(result.time[r]), tolerance=1e-15).q
            zetas = [q[moved.system.block(k)][7:] for k in range(len(moved.bodies))]
            peaks.append(
                [
                    corner_stress(body.mesh_model, body.reduction.basis, zeta, int(at[0]), int(at[1]), average)
                    for body, zeta, at, average in zip(
                        moved.bodies, zetas, exact.peak_stress_corner[r], averages, strict=True
                    )
                ]
            )
            norms.append(
                [
                    stress_norm_at(body.mesh_model, body.reduction.basis, zeta, average=average)
                    for body, zeta, average in zip(moved.bodies, zetas, averages, strict=True)
                ]
            )
        return np.array(peaks), np.array(norms)

    sides = {s: (outputs(s * step), outputs(-s * step)) for s in (1.0, 2.0)}
    for index, ours in ((0, exact.peak_stress_slopes), (1, exact.stress_norm_slopes)):
        assert ours is not None
        central = {s: (plus[index] - minus[index]) / (2 * s * step) for s, (plus, minus) in sides.items()}
        theirs = (4 * central[1.0] - central[2.0]) / 3
        print("averaged", index, np.abs(ours[ROWS, :, 0] - theirs).max() / np.abs(theirs).max())
        assert np.abs(theirs[:, link]).max() > 0.1 * np.abs(theirs).max()  # the morphed link's own stress moves
        np.testing.assert_allclose(ours[ROWS, :, 0], theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())
