"""Benchmark: our Hurty/Craig-Bampton reduction against Exudyn's on the same matrices.

One Bennett link (ffrf.geometry.link_geometry, paper axes) is meshed at several edge
lengths; ``ffrf.reduction.craig_bampton`` and Exudyn's
``FEMinterface.ComputeHurtyCraigBamptonModes(RBE2, excludeRigidBodyMotion=True)``
reduce the same nodes, M, K, bores and weights in the same process. Reported:
wall times, the ratio ours/Exudyn and the largest relative difference of the
fixed-interface frequencies. Optionally the inertia invariants are timed too
(ours vs Exudyn's ``ObjectFFRFreducedOrderInterface``, which forms a dense Psi~).

Usage::

    .venv/bin/python bench/bench_craig_bampton.py                 # 4, 2 and 1 mm, 32 modes
    .venv/bin/python bench/bench_craig_bampton.py --h 4 2 --invariants

The machine may be shared: every timing is the best of ``--repeat`` runs, ours
and Exudyn's alternating. With 2 cores, ``OPENBLAS_NUM_THREADS=1`` makes ARPACK's
level-2 BLAS work faster for both codes; report the setting with the numbers.
"""

from __future__ import annotations

import argparse
import gc
import time

import numpy as np


def build_link(h_mm: float, link: int):
    from ffrf.fe.fe_model import FEModel
    from ffrf.fe.interfaces import interface_from_group
    from ffrf.fe.materials import PLA
    from ffrf.geometry.joint_axes import paper_link_axes
    from ffrf.geometry.link_geometry import mesh_link

    axis_a, axis_b, names = paper_link_axes(link)
    mesh, _ = mesh_link(axis_a, axis_b, h=h_mm * 1e-3, names=names)
    model = FEModel.from_tet_mesh(mesh, PLA)
    return model, [interface_from_group(model, name) for name in names]


def time_ours(model, interfaces, n_modes: int, verify: bool):
    from ffrf.reduction.craig_bampton import craig_bampton

    start = time.perf_counter()
    result = craig_bampton(model, interfaces, n_modes, verify_mode_count=verify)
    return time.perf_counter() - start, result


def time_exudyn(model, interfaces, n_modes: int):
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    fem.nodes = {"Position": np.asarray(model.nodes)}
    fem.massMatrix, fem.stiffnessMatrix = model.mass, model.stiffness
    start = time.perf_counter()
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=[list(map(int, i.nodes)) for i in interfaces],
        nEigenModes=n_modes,
        useSparseSolver=True,
        computationMode=HCBstaticModeSelection.RBE2,
        boundaryNodesWeights=[np.asarray(i.weights) for i in interfaces],
        excludeRigidBodyMotion=True,
        verboseMode=False,
        timerTreshold=10**12,
    )
    return time.perf_counter() - start, fem


def time_invariants(model, reduction, fem):
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    from ffrf.reduction.invariants import inertia_invariants

    start = time.perf_counter()
    ours = inertia_invariants(model, reduction)
    t_ours = time.perf_counter() - start
    fem.modeBasis = {"matrix": reduction.basis, "type": "HCBmodes"}
    fem.surface = []
    start = time.perf_counter()
    theirs = ObjectFFRFreducedOrderInterface(fem)
    t_theirs = time.perf_counter() - start
    error = np.abs(ours.m_psi_tilde_psi_tilde - theirs.mPsiTildePsiTilde).max() / np.abs(theirs.mPsiTildePsiTilde).max()
    return t_ours, t_theirs, error


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, nargs="+", default=[4.0, 2.0, 1.0], help="edge lengths in mm")
    parser.add_argument("--modes", type=int, default=32, help="fixed-interface modes n_m (paper: 32)")
    parser.add_argument("--link", type=int, default=1, help="link index 0..3 (paper axes)")
    parser.add_argument("--invariants", action="store_true", help="also time the inertia invariants")
    parser.add_argument("--repeat", type=int, default=2, help="best of this many runs per code")
    args = parser.parse_args()

    header = (
        f"{'h/mm':>5} {'nodes':>8} {'DOFs':>8} {'ours/s':>8} {'ours,no Sturm/s':>16} {'Exudyn/s':>9} "
        f"{'ratio':>6} {'max rel df':>11}"
    )
    import os

    print(
        f"link {args.link}, n_m = {args.modes}, RBE2 bores, frame on the first bore, best of {args.repeat}, "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
    )
    print(header)
    for h in args.h:
        start = time.perf_counter()
        model, interfaces = build_link(h, args.link)
        t_mesh = time.perf_counter() - start
        t_fast = t_ours = t_exu = np.inf
        for _ in range(args.repeat):
            gc.collect()
            t_fast = min(t_fast, time_ours(model, interfaces, args.modes, verify=False)[0])
            gc.collect()
            elapsed, ours = time_ours(model, interfaces, args.modes, verify=True)
            t_ours = min(t_ours, elapsed)
            gc.collect()
            elapsed, fem = time_exudyn(model, interfaces, args.modes)
            t_exu = min(t_exu, elapsed)
        df = np.abs(ours.fixed_interface_frequencies_hz / np.sort(fem.GetEigenFrequenciesHz()) - 1).max()
        print(
            f"{h:5.1f} {len(model.nodes):8d} {3 * len(model.nodes):8d} {t_ours:8.2f} {t_fast:16.2f} {t_exu:9.2f} "
            f"{t_ours / t_exu:6.2f} {df:11.1e}   (meshing + assembly {t_mesh:.1f} s)",
            flush=True,
        )
        if args.invariants:
            t_inv, t_inv_exu, error = time_invariants(model, ours, fem)
            print(
                f"      invariants: ours {t_inv:.2f} s, Exudyn {t_inv_exu:.2f} s, ratio {t_inv / t_inv_exu:.3f}, "
                f"max rel diff M_PsiTildePsiTilde {error:.1e}",
                flush=True,
            )
        del model, interfaces, ours, fem
        gc.collect()


if __name__ == "__main__":
    main()
