"""Time per step against mesh size: a real Bennett link (link 1) hinged at its first bore and
swinging under gravity, meshed at 4, 2 (and, with --fine, 1) mm, always 6 + 8 modes.

Our FFRF body costs O(m^2) per evaluation from the modal moments and its bore markers O(m)
from precomputed matrices, so the time per step should not grow with the mesh; Exudyn's
MarkerSuperElementRigid loops over every bore node on every residual. Both run the same
scene (same nodes, M, K, basis, weights, rho_inf, step) in the same process, full Newton and
modified Newton; ours is reported warm (kernels compiled and cached).

Run: .venv/bin/python bench/bench_ffrf_step_cost.py [--fine] [--steps 300]
"""

import argparse

import numpy as np
import scipy.sparse as sp

from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import interface_from_group
from ffrf.fe.materials import PLA
from ffrf.geometry.joint_axes import paper_link_axes
from ffrf.geometry.link_geometry import mesh_link
from ffrf.reduction.craig_bampton import craig_bampton
from validation.exudyn_ffrf import run_exudyn, run_ffrf
from validation.reduced_body import ReducedBody
from validation.single_body_scenes import pendulum_scene


def link_body(h: float, n_modes: int = 8) -> ReducedBody:
    first, second, names = paper_link_axes(1)
    mesh, _ = mesh_link(first, second, h=h, names=names, name="link1")
    model = FEModel.from_tet_mesh(mesh, PLA, 1)
    bores = [interface_from_group(model, name) for name in names]
    basis = craig_bampton(model, bores, n_modes).basis
    return ReducedBody(
        model.nodes,
        sp.csr_matrix(model.mass),
        sp.csr_matrix(model.stiffness),
        basis,
        bores[0].nodes,
        bores[0].weights,
        bores[1].nodes,
        bores[1].weights,
        0.11,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fine", action="store_true", help="also the 1 mm mesh (about 150k DOFs, minutes)")
    parser.add_argument("--steps", type=int, default=300)
    args = parser.parse_args()
    sizes = (4e-3, 2e-3, 1e-3) if args.fine else (4e-3, 2e-3)
    print(
        f"{'h [mm]':>7} {'nodes':>7} {'bore nodes':>10} {'m':>3} | {'ours ms/step':>12} {'it':>5} | "
        f"{'Exudyn ms/step':>14} {'it':>5} | {'Exudyn mod. ms':>14} | ratio ours/Exudyn"
    )
    for h in sizes:
        body = link_body(h)
        scene = pendulum_scene(body, step=1e-3, t_end=args.steps * 1e-3, axis=(0.0, 1.0, 0.0))  # swings under gravity
        run_ffrf(pendulum_scene(body, step=1e-3, t_end=0.01))  # compile / load the numba cache
        ours = run_ffrf(scene)
        full = run_exudyn(scene, modified_newton=False)
        modified = run_exudyn(scene, modified_newton=True)
        n = args.steps
        diff = np.abs(ours.tracked - full.tracked).max()
        print(
            f"{1e3 * h:7.1f} {len(body.nodes):7d} {len(body.frame_nodes):10d} {body.n_modes:3d} | "
            f"{1e3 * ours.integration_time / n:12.3f} {ours.newton_iterations / n:5.2f} | "
            f"{1e3 * full.integration_time / n:14.3f} {full.newton_iterations / n:5.2f} | "
            f"{1e3 * modified.integration_time / n:14.3f} | {ours.integration_time / full.integration_time:6.2f}"
            f"   (max tracked-node difference {diff:.1e} m)"
        )


if __name__ == "__main__":
    main()
