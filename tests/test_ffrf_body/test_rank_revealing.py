"""The rank rule of ffrf/numerics/rank_revealing.py (docs/formulation.md, Eq. (R1)): the verdict "singular,
with so many free motions" and the solutions do not change under round-off, on synthetic matrices
with a known null space and on the static tangents of the test fixtures."""

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from body_fixtures import two_bar_chain
from pendulum_fixtures import pendulum

from ffrf.errors import StaticDivergence
from ffrf.numerics.rank_revealing import equilibration, factor, rank_tolerance, singular_values
from ffrf.paper.bennett_scene import assemble, build_bennett
from ffrf.solvers.static_solver import static_equilibrium

ROUND_OFF = 1e-15  # relative perturbation of every entry: what another BLAS kernel's rounding can change


def _perturbed(rng, matrix):
    return matrix * (1.0 + ROUND_OFF * rng.uniform(-1.0, 1.0, size=matrix.shape))


def _singular_matrix(rng, n=40, deficiency=3):
    """A badly scaled n x n matrix of known rank n - deficiency, its null space and its range."""
    u = np.linalg.qr(rng.normal(size=(n, n)))[0]
    v = np.linalg.qr(rng.normal(size=(n, n)))[0]
    sigma = np.logspace(0, -6, n)
    sigma[n - deficiency :] = 0.0
    scales = 10.0 ** rng.uniform(-8, 8, size=n)  # rows of stiffness and of constraints
    return scales[:, None] * ((u * sigma) @ v.T), v[:, n - deficiency :], scales[:, None] * u[:, : n - deficiency]


def test_synthetic_rank_is_the_same_under_round_off(rng):
    matrix, _, _ = _singular_matrix(rng)
    verdicts = {factor(_perturbed(rng, matrix)).rank_deficiency for _ in range(100)}
    assert verdicts == {3}
    regular = matrix + np.diag(10.0 ** rng.uniform(-8, 8, size=40))
    assert {factor(_perturbed(rng, regular)).rank_deficiency for _ in range(20)} == {0}


def test_singular_solve_is_the_minimum_norm_least_squares_solution(rng):
    """For a consistent right-hand side, A x = b, and x has no component in the null space of the
    equilibrated matrix (the minimum-norm solution in the equilibrated unknowns)."""
    matrix, _, range_ = _singular_matrix(rng)
    rhs = range_ @ rng.normal(size=range_.shape[1])
    solved = factor(matrix)
    x = solved.solve(rhs)
    assert np.abs(matrix @ x - rhs).max() <= 1e-8 * np.abs(rhs).max()
    rows, cols = equilibration(matrix)
    _, _, vt = np.linalg.svd(rows[:, None] * matrix * cols[None, :])
    null_scaled = vt[-3:].T
    assert np.abs(null_scaled.T @ (x / cols)).max() <= 1e-10 * np.abs(x / cols).max()


def test_non_finite_matrix_is_refused():
    matrix = np.eye(3)
    matrix[1, 2] = np.nan
    with pytest.raises(FloatingPointError, match="not finite"):
        factor(matrix, what="test matrix")


@pytest.fixture(scope="module")
def chain():
    return two_bar_chain()


def _static_tangent(system, q):
    zeros = np.zeros(system.n_coordinates)
    return system.iteration_matrix(q, zeros, zeros, np.zeros(system.n_constraints), 0.0, 0.0, 1.0, 0.0)


def test_chain_tangent_has_two_free_motions_on_every_rounding(rng, chain):
    """Bar 1 keeps a free translation and a free rotation: two zero singular values, computed at
    round-off (measured <= 1.3e-15 of the largest), well below the threshold n eps (9.8e-15)."""
    weightless = replace(chain, gravity=np.zeros(3))  # gravity would stiffen bar 1's free rotation
    tangent = _static_tangent(weightless, chain.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]))
    rows, cols = equilibration(tangent)
    sigma = singular_values(rows[:, None] * tangent * cols[None, :], compute_uv=False)
    relative = sigma / sigma[0]
    assert relative[-1] < relative[-2] < 0.2 * rank_tolerance(sigma.size)
    assert relative[-3] > 1e6 * rank_tolerance(sigma.size)  # measured 1.4e-2: the bars' softest direction
    assert {factor(_perturbed(rng, tangent)).rank_deficiency for _ in range(50)} == {2}


class _RoundedModel:
    """The chain with every static tangent perturbed by round-off, as another BLAS kernel would."""

    def __init__(self, system, rng):
        self.system, self.rng = system, rng

    def __getattr__(self, name):
        return getattr(self.system, name)

    def iteration_matrix(self, *args):
        return _perturbed(self.rng, self.system.iteration_matrix(*args))


def test_chain_equilibrium_is_the_same_under_round_off(chain, monkeypatch):
    """The issue's failure: on some kernels the free motions' singular values landed just above the
    old threshold (1e-15), their inverse entered the Newton step, and Newton ran out of iterations.
    Now the same equilibrium (to the Newton tolerance) comes out under ten different roundings, and
    with gravity the mechanism is reported as one (no equilibrium exists: bar 1 swings freely)."""
    from ffrf.solvers import static_solver

    weightless = replace(chain, gravity=np.zeros(3))
    q0 = chain.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    reference = static_equilibrium(weightless, q0, fast_path=False).q
    for seed in range(10):
        monkeypatch.setattr(
            static_solver,
            "newton_model",
            lambda system, fast, seed=seed: _RoundedModel(system, np.random.default_rng(seed)),
        )
        q = static_equilibrium(weightless, q0).q
        assert np.abs(q - reference).max() <= 1e-10 * np.abs(reference).max()
        assert np.abs(weightless.constraint_values(q, 0.0)).max() <= 1e-10
    monkeypatch.undo()
    # bar 1's free translation, and its rotation where gravity's geometric stiffness at the iterate Newton gives up
    # on leaves it free: which iterate that is depends on round-off
    with pytest.raises(StaticDivergence, match=r"singular \([12] free motion"):
        static_equilibrium(chain, q0, fast_path=False)


def test_near_rigid_bennett_keeps_its_small_physical_singular_values(monkeypatch):
    """Links of 1e15 Pa make three constraints of the closed loop nearly redundant; their singular
    values (measured 1.9e-10 of the largest at the assembly, down to 6.0e-13 along a revolution)
    are physics, not round-off: they must stay above the threshold n eps (2.3e-14 at n = 105), so
    that no tangent of the revolution is taken as singular."""
    from ffrf.solvers import static_solver

    scene = build_bennett("rigid", h=6e-3, order=1, n_modes=4)
    assembly = assemble(scene)
    smallest, deficiencies = [], []

    def recording_factor(matrix, what="matrix"):
        rows, cols = equilibration(matrix)
        sigma = singular_values(rows[:, None] * matrix * cols[None, :], compute_uv=False)
        smallest.append(sigma[-1] / sigma[0])
        factored = factor(matrix, what)
        deficiencies.append(factored.rank_deficiency)
        return factored

    monkeypatch.setattr(static_solver, "factor", recording_factor)
    static_solver.quasi_static(scene.system, assembly.q, np.linspace(0.0, scene.t_end, 121))
    assert min(smallest) < 1e-11  # the hard regime is reached (measured 6.0e-13)
    assert min(smallest) > 10.0 * rank_tolerance(scene.system.n_coordinates + scene.system.n_constraints)
    assert set(deficiencies) == {0}


def test_redundant_hinge_gives_unique_accelerations_and_shared_reactions():
    """A rigid pendulum held by the same hinge twice: the constraint matrix of Eq. (G4) is
    singular (5 redundant rows), the accelerations are still those of the single hinge, and the
    minimum-norm multipliers split the single hinge's reaction equally between the two copies."""
    from ffrf.solvers.common import consistent_accelerations

    system = pendulum(n_modes=0)[0]
    twice = replace(system, constraints=system.constraints + system.constraints)
    q = system.initial_state()
    qd = np.zeros_like(q)
    qdd_single, lam_single = consistent_accelerations(system, q, qd)
    qdd_twice, lam_twice = consistent_accelerations(twice, q, qd)
    np.testing.assert_allclose(qdd_twice, qdd_single, rtol=0, atol=1e-12 * np.abs(qdd_single).max())
    # multipliers: the Euler-parameter normalisation first (not repeated), then each hinge copy
    hinge = lam_single[1:]
    assert lam_twice.size == 1 + 2 * hinge.size
    np.testing.assert_allclose(lam_twice[0], lam_single[0], rtol=1e-12)
    for copy in (lam_twice[1 : 1 + hinge.size], lam_twice[1 + hinge.size :]):
        np.testing.assert_allclose(copy, 0.5 * hinge, rtol=0, atol=1e-12 * np.abs(hinge).max())


def test_singular_iteration_matrix_stops_the_run_with_partial_results():
    from ffrf.errors import SingularIterationMatrix
    from ffrf.solvers.generalized_alpha import generalized_alpha

    system = pendulum(n_modes=0)[0]
    twice = replace(system, constraints=system.constraints + system.constraints)
    q = system.initial_state()
    with pytest.raises(SingularIterationMatrix, match=r"singular \(\d+ zero singular value") as info:
        generalized_alpha(twice, q, np.zeros_like(q), 0.01, 1e-3)
    assert not info.value.partial.complete
    assert info.value.partial.q.shape == (1, q.size)  # the start, kept


_KERNEL_RUN = """
import sys
sys.path[:0] = [{tests!r}]
from dataclasses import replace
import numpy as np
from body_fixtures import two_bar_chain
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import static_equilibrium
chain = two_bar_chain()
q0 = chain.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
q0 = static_equilibrium(replace(chain, gravity=np.zeros(3)), q0).q
run = generalized_alpha(chain, q0, np.zeros_like(q0), 0.05, 1e-3)
np.savez({out!r}, q0=q0, q=run.q)
"""


def _run_in_process(path, kernel: str | None):
    """Run _KERNEL_RUN in a fresh Python with OpenBLAS's ``kernel`` (None: the one it detects)."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    if kernel is not None:
        env["OPENBLAS_CORETYPE"] = kernel
    script = _KERNEL_RUN.format(tests=str(Path(__file__).resolve().parents[1]), out=str(path))
    return subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def detected_kernel_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("kernels") / "detected.npz"
    result = _run_in_process(path, None)
    assert result.returncode == 0, result.stderr[-2000:]
    return np.load(path)


@pytest.mark.parametrize("kernel", ["Haswell", "Zen", "Sandybridge", "Prescott"])
def test_chain_results_agree_across_blas_kernels(kernel, tmp_path, detected_kernel_run):
    """The issue's reproduction, run in a fresh process per OpenBLAS kernel (Haswell and Zen
    failed before the rank rule) and compared with the kernel OpenBLAS detects on this CPU: the
    equilibrium and the dynamic trajectory from it agree to the Newton tolerance (measured: at
    most 1e-12 m apart)."""
    env = dict(os.environ, OPENBLAS_CORETYPE=kernel)
    probe = subprocess.run(
        [sys.executable, "-c", "import numpy as np; np.linalg.solve(np.eye(3) + 1, np.ones(3))"],
        env=env,
        capture_output=True,
        timeout=120,
    )
    if probe.returncode != 0:
        pytest.skip(f"this CPU cannot execute OpenBLAS's {kernel} kernel")  # not a failure of our code
    result = _run_in_process(tmp_path / "run.npz", kernel)
    assert result.returncode == 0, result.stderr[-2000:]
    theirs = np.load(tmp_path / "run.npz")
    np.testing.assert_allclose(theirs["q0"], detected_kernel_run["q0"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(theirs["q"], detected_kernel_run["q"], rtol=0, atol=1e-10)
