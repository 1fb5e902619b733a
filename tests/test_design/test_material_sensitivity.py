"""Exact derivatives of equilibria with respect to the links' Young's modulus and density (Eq. (D1), issue #35),
against a closed form and against re-solved equilibria of the perturbed linkage."""

from dataclasses import replace

import numpy as np
import pytest
from body_fixtures import clamped_cantilever

from ffrf.errors import SensitivityError
from ffrf.fe.materials import PLA
from ffrf.output.assembly_stress import scene_assembly_stress
from ffrf.output.peak_stress import corner_stress, p_norm, stress_norm_at
from ffrf.output.sensors import path_sensors
from ffrf.output.stress_average import ball_average
from ffrf.reduction.component_modes_post import von_mises_stress
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.path_sensitivity import material_sensitivity
from ffrf.solvers.equilibrium_sensitivity import equilibrium_response, material_rates
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.multibody import MultibodySystem

GRAVITY = np.array([0.0, 0.0, -9.81])


def _cantilever(n_modes: int = 4):
    model, _, basis, system = clamped_cantilever(n_modes, GRAVITY)
    return model, basis, system


def test_a_clamped_bar_sags_as_rho_over_e_and_so_do_its_derivatives():
    """A cantilever's sag under its weight is proportional to rho / E (the Ritz solution K_r zeta = Psi^T M g is
    linear in rho and in 1 / E), so d sag / d ln E = -sag and d sag / d ln rho = +sag, to round-off."""
    model, psi, system = _cantilever()
    solution = static_equilibrium(system, system.initial_state(), load_steps=1)
    dq, _ = equilibrium_response(system, solution.q, solution.multipliers, 0.0, material_rates(system, solution.q))
    tip = int(np.argmin(np.linalg.norm(model.nodes - [0.2, 0.01, 0.005], axis=1)))
    sag = (psi @ solution.q[7:])[3 * tip + 2]
    d_sag = (psi @ dq[7:])[3 * tip + 2]  # (2,): ln E, ln rho
    assert sag < -1e-4  # a real sag to scale by
    np.testing.assert_allclose(d_sag, [-sag, sag], rtol=1e-10)
    np.testing.assert_allclose(dq[:7], 0.0, atol=1e-14)  # the clamped frame does not move


@pytest.fixture(scope="module")
def bennett_path():
    from bench import hard_cases

    scene = hard_cases.make_scene(PLA, h=8e-3, order=1, n_modes=2)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    return scene, result


@pytest.mark.parametrize("parameter", [("E", 1), ("rho", 2), ("E", 3)])
def test_the_coupler_and_torque_derivatives_agree_with_re_solved_perturbed_linkages(bennett_path, parameter):
    """The PLA Bennett (coarse links) along part of its revolution: the derivatives of the coupler point, the
    driving torque and every joint's reaction force by Eq. (D1) (the clamp's by a link's density: that link's
    weight, as statics says) agree with central differences of equilibria re-solved by Newton for the linkage with
    that link's E or rho times exp(+-1e-3) and exp(+-2e-3), combined by Richardson's rule, within 1e-6 of the largest
    derivative (measured: 4e-8, the re-solved equilibria's round-off over the steps; one step's differences alone are
    off by about 2e-7, the step squared). The lowest squared frequency of Eq. (B1) likewise, within 1e-6 of the
    largest squared frequency (measured 1e-7: both sides' eigenvalue round-off, 1e-10 of mu, over the steps). Every
    link's peak von Mises stress likewise (Eq. (D9)): the peak is the whole stress field's as the assembly report
    computes it, and its derivative, that of the stress at the peak's corner, agrees with the re-solved linkages'
    stress at that corner within 1e-6 of the largest (measured 7e-10 to 8e-9); the p-norm of each link's corner
    stresses (Eq. (D10)) too, against the norms of the re-solved linkages' whole fields."""
    scene, result = bennett_path
    kind, link = parameter
    exact = material_sensitivity(
        scene, result.time, result.q, result.multipliers, links=(link,), stability=True, stress=True
    )
    column = 0 if kind == "E" else 1
    rows = [1, 3, 4]

    def outputs(change: float) -> dict:
        bodies = list(scene.system.bodies)
        factor = np.exp(change)
        bodies[link] = bodies[link].scaled(**({"stiffness": factor} if kind == "E" else {"density": factor}))
        system = replace(scene.system, bodies=tuple(bodies))
        solved = _re_solved(system, result, rows)
        q = np.array([s.q for s in solved])
        lam = np.array([s.multipliers for s in solved])
        mu = [_lowest(system, s, float(result.time[r])) for s, r in zip(solved, rows, strict=True)]
        peaks = np.array(
            [_at_corners(scene, s.q, exact.peak_stress_corner[r]) for s, r in zip(solved, rows, strict=True)]
        )
        norms = np.array([_norms(scene, s.q) for s in solved])
        if kind == "E":  # the FE model's E is the nominal one: the stress at a strain is proportional to E
            peaks[:, link] *= factor
            norms[:, link] *= factor
        return path_sensors(replace(scene, system=system), result.time[rows], q, lam) | {
            "multipliers": lam,
            "mu": np.array(mu),
            "peaks": peaks,
            "norms": norms,
        }

    def central(step: float, name: str) -> np.ndarray:
        return (outputs(step)[name] - outputs(-step)[name]) / (2 * step)

    coupler = (4 * central(1e-3, "coupler_point") - central(2e-3, "coupler_point")) / 3
    torque = (4 * central(1e-3, "driving_torque") - central(2e-3, "driving_torque")) / 3
    ours_coupler = exact.coupler_point[rows, :, column]
    ours_torque = exact.driving_torque[rows, column]
    assert np.abs(ours_coupler).max() > 1e-7  # the links' compliance moves the coupler
    np.testing.assert_allclose(ours_coupler, coupler, rtol=0, atol=1e-6 * np.abs(coupler).max())
    np.testing.assert_allclose(ours_torque, torque, rtol=0, atol=1e-6 * np.abs(torque).max())
    # every joint's reaction force: its first three multipliers, the response's own rows
    multipliers = (4 * central(1e-3, "multipliers") - central(2e-3, "multipliers")) / 3
    system = scene.system
    scale = max(
        np.abs(multipliers[:, int(system.rows[c]) : int(system.rows[c]) + 3]).max()
        for c, joint in enumerate(system.all_constraints)
        if joint.name in exact.reaction_forces
    )  # of all joints: a joint the parameter does not load has only round-off to compare
    for c, joint in enumerate(system.all_constraints):
        if joint.name in exact.reaction_forces:
            theirs = multipliers[:, int(system.rows[c]) : int(system.rows[c]) + 3]
            ours_force = exact.reaction_forces[joint.name][rows, :, column]
            np.testing.assert_allclose(ours_force, theirs, rtol=0, atol=1e-6 * scale)
    assert len(exact.reaction_forces) == 5  # the loop's four joints and the base's clamp
    mu = (4 * central(1e-3, "mu") - central(2e-3, "mu")) / 3
    assert exact.squared_frequency is not None and exact.lowest_squared_frequency is not None
    np.testing.assert_allclose(exact.squared_frequency[rows], outputs(0.0)["mu"], rtol=1e-9)
    scale = exact.squared_frequency.max()
    np.testing.assert_allclose(exact.lowest_squared_frequency[rows, column], mu, rtol=0, atol=1e-6 * scale)
    assert np.abs(mu).max() > 1e-3 * scale  # the material moves the frequency
    peaks = (4 * central(1e-3, "peaks") - central(2e-3, "peaks")) / 3
    assert exact.peak_stress is not None and exact.peak_stress_slopes is not None
    whole = [[body.max_von_mises_pa for body in scene_assembly_stress(scene, result.q[r]).links] for r in rows]
    np.testing.assert_allclose(exact.peak_stress[rows], whole, rtol=1e-12)  # the whole field's peak
    np.testing.assert_allclose(
        exact.peak_stress_slopes[rows, :, column], peaks, rtol=0, atol=1e-6 * np.abs(peaks).max()
    )
    norms = (4 * central(1e-3, "norms") - central(2e-3, "norms")) / 3
    assert exact.stress_norm is not None and exact.stress_norm_slopes is not None
    np.testing.assert_allclose(exact.stress_norm[rows], [_norms(scene, result.q[r]) for r in rows], rtol=1e-12)
    assert np.all(exact.stress_norm >= exact.peak_stress)  # never below the peak
    print("norm slopes", np.abs(exact.stress_norm_slopes[rows, :, column] - norms).max() / np.abs(norms).max())
    np.testing.assert_allclose(
        exact.stress_norm_slopes[rows, :, column], norms, rtol=0, atol=1e-6 * np.abs(norms).max()
    )
    # statics: the clamp carries the whole weight, so its vertical force changes with a link's density by that
    # link's weight and not at all with its modulus, at every pose
    weight = float(scene.system.bodies[link].moments.mass) * 9.81
    expected = -weight if kind == "rho" else 0.0
    clamp = exact.reaction_forces["clamp"][:, :, column]
    np.testing.assert_allclose(clamp[:, 2], expected, rtol=0, atol=1e-9 * weight)
    np.testing.assert_allclose(clamp[:, :2], 0.0, atol=1e-9 * weight)


def _re_solved(system: MultibodySystem, result, rows: list[int]) -> list:
    """The equilibria of ``system`` at ``result``'s rows, by Newton from them, polished from a freshly factored
    tangent (round-off, not the 1e-13 of the first solve)."""
    solved = []
    for r in rows:
        first = static_equilibrium(system, result.q[r], t=float(result.time[r]), tolerance=1e-13)
        solved.append(static_equilibrium(system, first.q, t=float(result.time[r]), tolerance=1e-15))
    return solved


def _lowest(system: MultibodySystem, solved, t: float) -> float:
    """The lowest squared frequency of Eq. (B1) at a solved equilibrium."""
    return float(equilibrium_stability(system, solved.q, solved.multipliers, t, count=1).squared_frequencies[0])


def _at_corners(scene, q: np.ndarray, corners: np.ndarray) -> list[float]:
    """Each link's von Mises stress at coordinates ``q`` at its (element, corner), from its whole displacement
    field (:meth:`FEModel.vertex_strains`), not from strain modes."""
    return [
        corner_stress(body.mesh_model, body.reduction.basis, q[scene.system.block(k)][7:], *corners[k])
        for k, body in enumerate(scene.bodies)
    ]


def _norms(scene, q: np.ndarray) -> list[float]:
    """Each link's norm of Eq. (D10) at coordinates ``q``, from its whole displacement field, not strain modes."""
    return [
        stress_norm_at(body.mesh_model, body.reduction.basis, q[scene.system.block(k)][7:])
        for k, body in enumerate(scene.bodies)
    ]


def test_a_fold_is_refused_not_differentiated():
    """A free bar (nothing holds it) under gravity: its tangent is singular and gravity loads the free motion, so
    no equilibrium responds to its density; the error says so instead of a number."""
    _, _, clamped = _cantilever(2)
    free = MultibodySystem(clamped.bodies, (), gravity=GRAVITY)
    q = free.initial_state()
    with pytest.raises(SensitivityError, match="fold"):
        equilibrium_response(free, q, np.zeros(free.n_constraints), 0.0, material_rates(free, q))


def test_scaling_every_stiffness_and_density_together_moves_nothing_and_scales_the_torque(bennett_path):
    """Every link's E and rho times one factor: the same equilibrium (K_r zeta = Q_g scale alike), forces and so the
    driving torque times that factor. So the derivatives by E and rho of all links sum to zero for the coupler
    point and to the torque itself for the torque (exact identities of statics, not of our formulation). The forces
    and the masses scale alike, so the frequencies of small vibrations do not move: the lowest squared frequency's
    derivatives sum to zero too (measured 1.5e-7 of the largest, the eigenvalue's round-off over the step); the
    strains stay while every E grows, so each link's peak stress grows with it: its derivatives sum to it (and so do
    the derivatives of its norm, Eq. (D10))."""
    scene, result = bennett_path
    exact = material_sensitivity(scene, result.time, result.q, result.multipliers, stability=True, stress=True)
    assert exact.lowest_squared_frequency is not None
    slopes = exact.lowest_squared_frequency
    np.testing.assert_allclose(slopes.sum(axis=1), 0.0, atol=1e-6 * np.abs(slopes).max())
    # the strains stay, E scales: every link's peak stress scales too (measured 1.8e-11)
    assert exact.peak_stress is not None and exact.peak_stress_slopes is not None
    np.testing.assert_allclose(exact.peak_stress_slopes.sum(axis=2), exact.peak_stress, rtol=1e-9)
    assert exact.stress_norm is not None and exact.stress_norm_slopes is not None
    np.testing.assert_allclose(exact.stress_norm_slopes.sum(axis=2), exact.stress_norm, rtol=1e-9)
    np.testing.assert_allclose(exact.coupler_point.sum(axis=2), 0.0, atol=1e-9 * np.abs(exact.coupler_point).max())
    torque = result.sensors["driving_torque"]
    np.testing.assert_allclose(exact.driving_torque.sum(axis=1), torque, rtol=1e-8, atol=1e-10 * np.abs(torque).max())
    assert exact.mass is not None  # the mass scales with the density alone: its derivatives sum to the mass
    assert exact.mass.sum() == pytest.approx(sum(body.moments.mass for body in scene.system.bodies), rel=1e-12)
    np.testing.assert_array_equal(exact.mass[: len(scene.system.bodies)], 0.0)


def test_without_gravity_the_squared_frequencies_go_as_e_over_rho(bennett_path):
    """Without gravity the held linkage rests unstrained (no load, no reaction), so its stiffness is the links'
    elastic one alone, proportional to E, and its mass proportional to rho: every squared frequency goes as E / rho,
    and the lowest one's derivatives by all links' ln E sum to it, by all links' ln rho to minus it (Euler's rule for
    homogeneous functions; measured 1e-9)."""
    scene, _ = bennett_path
    weightless = replace(scene, system=replace(scene.system, gravity=np.zeros(3)))
    result = run_linkage(weightless, mode="quasi_static", n_outputs=3, t_end=0.2 * scene.t_end, sensors="path")
    exact = material_sensitivity(weightless, result.time, result.q, result.multipliers, stability=True)
    assert exact.squared_frequency is not None and exact.lowest_squared_frequency is not None
    mu, k = exact.squared_frequency, len(scene.system.bodies)
    np.testing.assert_allclose(exact.lowest_squared_frequency[:, :k].sum(axis=1), mu, rtol=1e-6)
    np.testing.assert_allclose(exact.lowest_squared_frequency[:, k:].sum(axis=1), -mu, rtol=1e-6)
    np.testing.assert_allclose(exact.coupler_point, 0.0, atol=1e-12)  # nothing loads it: nothing moves


@pytest.fixture(scope="module")
def misfit_bennett():
    """The paper's Bennett from its DH table, coarse PLA links, bore errors as misfits (the studies' model), along
    part of its revolution."""
    from ffrf.scenes.linkage_file import linkage_options
    from ffrf.scenes.linkage_scene import build_linkage

    dh = {"a": [110, 220, 110, 220], "alpha_deg": [150, 90, 150, 90]}
    document = {"linkage": {"dh": dh, "unit": "mm", "driver": 3, "tool_link": 2, "start_angle_deg": -90.0}}
    document["linkage"] |= {"h": 0.008, "order": 1, "modes": 2}
    loop, options, _ = linkage_options(document)
    options = replace(options, bore_error_model="misfit")
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    return loop, options, scene, result


@pytest.mark.parametrize(
    "field, joint, link, delta",
    [("twist", 3, 0, 5e-5), ("offset", 1, 1, 1e-5), ("axial", 2, 3, 1e-5), ("twist", 1, 2, 5e-5)],
)
def test_bore_error_derivatives_agree_with_linkages_built_with_the_error(misfit_bennett, field, joint, link, delta):
    """Eq. (D1) for a bore error (twist, rad; offset along the link's normal and axial, m; on the coupler link 2 the
    coupler point, the mean of its joint points as built, moves with its bore too) against central
    differences of the linkage built with that BoreError (the misfit model's own build: joints from the erroneous
    bore) and its equilibria re-solved by Newton at the same poses, at +-delta and +-2 delta combined by Richardson's
    rule (truncation delta^4; one step's differences are off by about 1e-5 of the derivative at delta = 2e-5 m, as
    delta squared), within 1e-6 of the largest derivative (measured: 1e-10 to 2e-10 for the coupler, up to 2e-7 for
    the torque). The lowest squared frequency of Eq. (B1) at steps five times as wide, within 1e-5 (measured 1.2e-6
    to 2.5e-6: on both sides the eigenvalue's round-off, 1e-10 of it as the links' stiffest modes are 1e6 times the
    lowest, over the steps). Every link's peak von Mises stress likewise (at the peak's corner: a bore error moves
    the peak between corners whose stresses are close), within 1e-6."""
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.scenes.linkage_scene import build_linkage
    from ffrf.scenes.path_sensitivity import bore_sensitivity

    loop, options, scene, result = misfit_bennett
    exact = bore_sensitivity(
        scene, loop, options, result.time, result.q, result.multipliers, ((joint, link),), stability=True, stress=True
    )
    column = ("twist", "offset", "axial").index(field)
    assert exact.parameters[column] == f"{field} joint{joint} link{link}"
    rows = [1, 3, 4]

    def outputs(error: float) -> dict:
        built = build_linkage(loop, replace(options, bore_errors=(BoreError.single(joint, link, field, error),)))
        solved = _re_solved(built.system, result, rows)
        q = np.array([s.q for s in solved])
        lam = np.array([s.multipliers for s in solved])
        mu = [_lowest(built.system, s, float(result.time[r])) for s, r in zip(solved, rows, strict=True)]
        peaks = [_at_corners(built, s.q, exact.peak_stress_corner[r]) for s, r in zip(solved, rows, strict=True)]
        return path_sensors(built, result.time[rows], q, lam) | {"mu": np.array(mu), "peaks": np.array(peaks)}

    def central(step: float, name: str) -> np.ndarray:
        return (outputs(step)[name] - outputs(-step)[name]) / (2 * step)

    coupler = (4 * central(delta, "coupler_point") - central(2 * delta, "coupler_point")) / 3
    torque = (4 * central(delta, "driving_torque") - central(2 * delta, "driving_torque")) / 3
    ours_coupler, ours_torque = exact.coupler_point[rows, :, column], exact.driving_torque[rows, column]
    assert np.abs(ours_coupler).max() > 1e-3  # a bore error moves the coupler far more than gravity's sag
    np.testing.assert_allclose(ours_coupler, coupler, rtol=0, atol=1e-6 * np.abs(coupler).max())
    np.testing.assert_allclose(ours_torque, torque, rtol=0, atol=1e-6 * np.abs(torque).max())
    wide = 5 * delta  # an eigenvalue's round-off (1e-10 of it) needs a wider step
    mu = (4 * central(wide, "mu") - central(2 * wide, "mu")) / 3
    assert exact.lowest_squared_frequency is not None
    ours = exact.lowest_squared_frequency[rows, column]
    np.testing.assert_allclose(ours, mu, rtol=0, atol=1e-5 * np.abs(mu).max())
    narrow = delta / 10  # a misfit's stress bends fast with the error: a tenth of the step keeps the truncation low
    peaks = (4 * central(narrow, "peaks") - central(2 * narrow, "peaks")) / 3
    assert exact.peak_stress_slopes is not None
    slopes = exact.peak_stress_slopes[rows, :, column]
    np.testing.assert_allclose(slopes, peaks, rtol=0, atol=1e-6 * np.abs(peaks).max())


@pytest.fixture(scope="module")
def misfit_6r():
    """Rational Linkages' collisions_free_6r at a tenth of its size, coarse PLA links, bore errors as misfits,
    along part of its revolution."""
    from ffrf.scenes.linkage_description import LinkageOptions
    from ffrf.scenes.linkage_scene import build_linkage
    from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start

    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, scale=0.1)
    origin = regular_start(mechanism, loop)
    options = LinkageOptions(
        h=12e-3, order=1, n_modes=2, start_angle=float(origin[0]), origin=origin, bore_error_model="misfit"
    )
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    return loop, options, scene, result


@pytest.mark.parametrize("field, joint, link", [("twist", 2, 2), ("offset", 4, 5)])
def test_a_6r_s_bore_error_derivatives_agree_with_linkages_built_with_the_error(misfit_6r, field, joint, link):
    """Eq. (D1) on a 6R (collisions_free_6r, six joints, five moving links): the coupler point's and the driving
    torque's derivatives by a bore's twist (rad) or offset (m) against central differences of the linkage built with
    that BoreError and its equilibria re-solved by Newton, at +-delta and +-2 delta combined by Richardson's rule,
    within 1e-6 of the largest derivative, as on the Bennett (measured: 1e-10 to 3e-10 for the coupler, 2e-11 to
    2e-10 for the torque)."""
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.scenes.linkage_scene import build_linkage
    from ffrf.scenes.path_sensitivity import bore_sensitivity

    loop, options, scene, result = misfit_6r
    exact = bore_sensitivity(scene, loop, options, result.time, result.q, result.multipliers, ((joint, link),))
    column = ("twist", "offset", "axial").index(field)
    rows = [1, 3, 4]
    delta = 5e-5 if field == "twist" else 1e-5

    def outputs(error: float) -> dict:
        built = build_linkage(loop, replace(options, bore_errors=(BoreError.single(joint, link, field, error),)))
        solved = _re_solved(built.system, result, rows)
        q = np.array([s.q for s in solved])
        return path_sensors(built, result.time[rows], q, np.array([s.multipliers for s in solved]))

    def central(step: float, name: str) -> np.ndarray:
        return (outputs(step)[name] - outputs(-step)[name]) / (2 * step)

    coupler = (4 * central(delta, "coupler_point") - central(2 * delta, "coupler_point")) / 3
    torque = (4 * central(delta, "driving_torque") - central(2 * delta, "driving_torque")) / 3
    ours_coupler, ours_torque = exact.coupler_point[rows, :, column], exact.driving_torque[rows, column]
    print(field, "coupler error", np.abs(ours_coupler - coupler).max() / np.abs(coupler).max())
    print(field, "torque error", np.abs(ours_torque - torque).max() / np.abs(torque).max())
    assert np.abs(ours_coupler).max() > 1e-3  # a bore error moves the coupler
    np.testing.assert_allclose(ours_coupler, coupler, rtol=0, atol=1e-6 * np.abs(coupler).max())
    np.testing.assert_allclose(ours_torque, torque, rtol=0, atol=1e-6 * np.abs(torque).max())


@pytest.mark.slow  # 52 s; material derivatives stay checked on the Bennett
def test_the_von_mises_trusss_apex_moves_with_the_bars_stiffness_as_its_closed_form(tmp_path):
    """The von Mises truss of two steel bars under a dead load P at the apex (tests/test_textbook): P = k h(z) with
    k = EA / L0 and h(z) = 2 (L0 - L) z / L, L = sqrt(a^2 + z^2), so at a fixed load the apex rises by
    dz / d ln E = -h(z) / h'(z) when both bars' E grow together; Eq. (D1) summed over the two bars gives it at every
    equilibrium of the run before the fold, a large-rotation equilibrium (the bars turn about their feet), to 1e-6
    of the largest (measured 4e-10; the FE bar's axial stiffness is EA / L0 to 1e-14, and at pinned ends it only
    stretches). Approaching the fold the derivative grows as 1 / h' (127-fold from 0.1 to 0.99 P_max)."""
    from ffrf import load
    from ffrf.output.sensors import joint_rows
    from ffrf.scenes.scene_file import load_scene
    from validation.textbook_cases import HALF_SPAN, LOAD_RATE, truss_closed_form, write_truss_scene

    c = truss_closed_form()
    scene = load_scene(write_truss_scene(tmp_path))
    run = load(scene).run()
    system = scene.system
    before = np.flatnonzero(run.time * LOAD_RATE < c["limit_load"])[1:]  # loaded, before the fold
    ours, exact = [], []
    for row in before:
        q, lam, t = run.q[row], run.multipliers[row], float(run.time[row])
        dq, _ = equilibrium_response(system, q, lam, t, material_rates(system, q))
        direction = dq[:, 0] + dq[:, 1]  # both bars' E together
        step = 1e-6 / np.abs(direction).max()
        sides = [
            joint_rows(system, [t], (q + s * step * direction)[None], lam[None])["apex_point1"][0, 2] for s in (1, -1)
        ]
        ours.append((sides[0] - sides[1]) / (2 * step))
        z = run.sensors["apex_point1"][row, 2]
        length = np.hypot(HALF_SPAN, z)
        h = 2.0 * (c["length"] - length) * z / length
        slope = 2.0 * (-(z**2) / length**2 + (c["length"] - length) * HALF_SPAN**2 / length**3)
        exact.append(-h / slope)
    ours, exact = np.array(ours), np.array(exact)
    np.testing.assert_allclose(ours, exact, rtol=0, atol=1e-6 * np.abs(exact).max())
    assert np.abs(exact[-1]) > 100.0 * np.abs(exact[0])


def test_the_averaged_stress_and_its_derivatives_agree_with_re_solved_linkages(bennett_path):
    """With a ``stress_radius`` (Eq. (D14)): each link's largest stress averaged over 4 mm balls is the largest of
    the averages of its whole displacement field (not strain modes, 1e-12), and its derivatives by link 3's E, and
    the p-norm's (Eq. (D10)), agree with the averaged stresses of equilibria re-solved for E times exp(+-1e-3) and
    exp(+-2e-3) (Richardson) within 1e-6 of the largest (measured 7e-9 for both)."""
    scene, result = bennett_path
    radius, link, rows = 4e-3, 3, [1, 3, 4]
    exact = material_sensitivity(
        scene, result.time, result.q, result.multipliers, links=(link,), stress=True, stress_radius=radius
    )
    averages = [ball_average(body.mesh_model, radius) for body in scene.bodies]

    def averaged(q: np.ndarray) -> tuple[list[float], list[float]]:
        fields = [
            average.strains(body.mesh_model, body.mesh_model.vertex_strains(body.reduction.basis @ zeta))
            for body, average, zeta in (
                (body, averages[k], q[scene.system.block(k)][7:]) for k, body in enumerate(scene.bodies)
            )
        ]
        stresses = [von_mises_stress(f, PLA.E, PLA.nu) for f in fields]
        return [float(s.max()) for s in stresses], [p_norm(s) for s in stresses]

    def outputs(change: float) -> tuple[np.ndarray, np.ndarray]:
        bodies = list(scene.system.bodies)
        bodies[link] = bodies[link].scaled(stiffness=np.exp(change))
        solved = _re_solved(replace(scene.system, bodies=tuple(bodies)), result, rows)
        peaks = np.array(
            [
                [
                    corner_stress(
                        body.mesh_model,
                        body.reduction.basis,
                        s.q[scene.system.block(k)][7:],
                        int(at[0]),
                        int(at[1]),
                        averages[k],
                    )
                    for k, (body, at) in enumerate(zip(scene.bodies, exact.peak_stress_corner[r], strict=True))
                ]
                for s, r in zip(solved, rows, strict=True)
            ]
        )
        norms = np.array([averaged(s.q)[1] for s in solved])
        peaks[:, link] *= np.exp(change)  # the FE model's E is the nominal one: stress at a strain goes as E
        norms[:, link] *= np.exp(change)
        return peaks, norms

    assert exact.peak_stress is not None and exact.stress_norm is not None
    whole = [averaged(result.q[r]) for r in rows]
    np.testing.assert_allclose(exact.peak_stress[rows], [w[0] for w in whole], rtol=1e-12)
    np.testing.assert_allclose(exact.stress_norm[rows], [w[1] for w in whole], rtol=1e-12)
    sides = {step: (outputs(step), outputs(-step)) for step in (1e-3, 2e-3)}
    for index, ours in ((0, exact.peak_stress_slopes), (1, exact.stress_norm_slopes)):
        assert ours is not None
        central = {step: (plus[index] - minus[index]) / (2 * step) for step, (plus, minus) in sides.items()}
        theirs = (4 * central[1e-3] - central[2e-3]) / 3
        print("averaged", index, np.abs(ours[rows, :, 0] - theirs).max() / np.abs(theirs).max())
        np.testing.assert_allclose(ours[rows, :, 0], theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())


def test_the_loaded_clearance_without_load_is_the_rigid_motions(misfit_bennett):
    """Without gravity the equilibria are the rigid motion's poses, and the clearance of the links placed as the
    model has them (frames and modes, Eq. (CL7)) is the rigid motion's clearance at the same drive angles
    (Eqs. (CL1)-(CL3)) for every pair, to 1e-12 m (measured 1.3e-15); under the links' weight it differs by their sag
    (measured up to 3.6e-5 m)."""
    from ffrf.output.clearance import clearance_at
    from ffrf.scenes.loaded_clearance import loaded_clearance

    _, _, scene, result = misfit_bennett
    unloaded = replace(scene, system=replace(scene.system, gravity=np.zeros(3)))
    run = run_linkage(unloaded, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    angles = np.array([scene.drive_angle(float(t)) for t in run.time])
    ours = loaded_clearance(unloaded, run.q)
    rows = np.repeat(ours.pairs, len(angles), axis=0)
    rigid = clearance_at(scene.link_solids(), scene.rigid_revolution(72), scene.joint_zones(), rows, np.tile(angles, 6))
    rigid = rigid.reshape(len(ours.pairs), len(angles)).T
    np.testing.assert_allclose(ours.distance, rigid, rtol=0, atol=1e-12)
    sagging = loaded_clearance(scene, result.q).distance
    assert 1e-6 < np.abs(sagging - rigid).max() < 1e-4


@pytest.mark.parametrize("field, joint, link, delta", [("twist", 3, 0, 5e-5), ("offset", 1, 1, 1e-5)])
def test_the_loaded_clearance_derivatives_by_bore_errors_agree_with_linkages_built_with_the_error(
    misfit_bennett, field, joint, link, delta
):
    """The clearance of every pair of links along the loaded motion (Eq. (CL7)) differentiated along the response of
    Eq. (D1) by a bore error, against the clearance of the linkage built with that BoreError at its equilibria
    re-solved by Newton at +-delta and +-2 delta (Richardson), within 1e-6 of the largest (measured 5e-9 for the
    twist, 3e-9 for the offset)."""
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.scenes.linkage_scene import build_linkage
    from ffrf.scenes.loaded_clearance import loaded_clearance
    from ffrf.scenes.path_sensitivity import bore_sensitivity

    loop, options, scene, result = misfit_bennett
    exact = bore_sensitivity(scene, loop, options, result.time, result.q, result.multipliers, ((joint, link),))
    column = ("twist", "offset", "axial").index(field)
    rows = [1, 3, 4]
    assert exact.coordinates is not None
    ours = loaded_clearance(scene, result.q[rows], exact.coordinates[rows][:, :, [column]])
    assert ours.slopes is not None

    def clearance(error: float) -> np.ndarray:
        built = build_linkage(loop, replace(options, bore_errors=(BoreError.single(joint, link, field, error),)))
        return loaded_clearance(built, np.array([s.q for s in _re_solved(built.system, result, rows)])).distance

    def central(step: float) -> np.ndarray:
        return (clearance(step) - clearance(-step)) / (2 * step)

    theirs = (4 * central(delta) - central(2 * delta)) / 3
    print(field, np.abs(ours.slopes[:, :, 0] - theirs).max() / np.abs(theirs).max())
    assert np.abs(theirs).max() > 1e-3  # the error moves the links against each other
    np.testing.assert_allclose(ours.slopes[:, :, 0], theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())


@pytest.mark.parametrize(
    "field, joint, link, delta", [("tilt", 3, 0, 5e-5), ("shift", 1, 1, 1e-5), ("tilt", 2, 3, 5e-5)]
)
def test_a_bore_s_tilt_and_shift_derivatives_agree_with_linkages_built_with_the_error(
    misfit_bennett, field, joint, link, delta
):
    """The two errors of a bore that leave the DH relation of the loop's axes (a tilt about the binormal, rad; a
    shift along it, m): the coupler point's and the driving torque's derivatives by Eq. (D1) against central
    differences of the linkage built with that BoreError, its equilibria re-solved by Newton at +-delta and
    +-2 delta (Richardson), within 1e-6 of the largest derivative, as for the other three (measured 1e-10 to
    6e-10)."""
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.scenes.linkage_scene import build_linkage
    from ffrf.scenes.path_sensitivity import bore_sensitivity

    loop, options, scene, result = misfit_bennett
    exact = bore_sensitivity(
        scene, loop, options, result.time, result.q, result.multipliers, ((joint, link),), fields=(field,)
    )
    assert exact.parameters == (f"{field} joint{joint} link{link}",)
    rows = [1, 3, 4]

    def outputs(error: float) -> dict:
        built = build_linkage(loop, replace(options, bore_errors=(BoreError.single(joint, link, field, error),)))
        solved = _re_solved(built.system, result, rows)
        q, lam = np.array([s.q for s in solved]), np.array([s.multipliers for s in solved])
        return path_sensors(built, result.time[rows], q, lam)

    def central(step: float, name: str) -> np.ndarray:
        return (outputs(step)[name] - outputs(-step)[name]) / (2 * step)

    for name, ours in (
        ("coupler_point", exact.coupler_point[rows, :, 0]),
        ("driving_torque", exact.driving_torque[rows, 0]),
    ):
        theirs = (4 * central(delta, name) - central(2 * delta, name)) / 3
        print(field, name, np.abs(ours - theirs).max() / np.abs(theirs).max())
        assert np.abs(theirs).max() > 0.0
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())
