"""Naive least-squares DH fit vs the paper's geometric identification, with 0.1 mm marker noise.

Run: .venv/bin/python bench/bench_identification_conditioning.py
Prints the condition number and weakest directions of the naive path Jacobian, and the
parameters each method recovers from the same noisy coupler data.
"""

import time

import numpy as np
from scipy.optimize import least_squares

from identification import LinkRecord, identify_record
from identification.naive_fit import PARAMETER_NAMES, coupler_path_model, naive_path_jacobian
from kinematics import BennettLinkage


def main(n_angles: int = 24, noise: float = 1e-4, seed: int = 1) -> None:
    rng = np.random.default_rng(seed)
    linkage = BennettLinkage.paper()
    truth = np.r_[linkage.a, linkage.alpha, np.zeros(4), [0.05, 0.03, 0.02]]
    start = time.perf_counter()
    jacobian = naive_path_jacobian(truth, n_angles)
    print(
        f"naive path Jacobian: condition number {jacobian.condition_number:.3e} ({time.perf_counter() - start:.1f} s)"
    )
    for line in jacobian.describe():
        print("  " + line)

    measured = coupler_path_model(truth, n_angles) + noise * rng.normal(size=3 * n_angles)
    guess = (
        truth
        + np.r_[
            2e-3 * rng.normal(size=4),
            np.radians(0.5) * rng.normal(size=4),
            1e-3 * rng.normal(size=4),
            2e-3 * rng.normal(size=3),
        ]
    )
    start = time.perf_counter()
    fit = least_squares(lambda p: coupler_path_model(p, n_angles) - measured, guess, diff_step=1e-6)
    print(
        f"naive fit: {fit.nfev} model evaluations, {time.perf_counter() - start:.1f} s, "
        f"rms residual {1e3 * np.sqrt(np.mean(fit.fun**2)):.4f} mm"
    )
    for name, value, true in zip(PARAMETER_NAMES, fit.x, truth, strict=True):
        unit, scale = ("deg", np.degrees(1)) if name.startswith("alpha") else ("mm", 1e3)
        print(
            f"  {name:7s} {scale * value:10.3f} {unit}  (true {scale * true:9.3f}, error {scale * (value - true):+.3f})"
        )

    # The geometric method on the same noise level, tracking links 1, 2, 3 (one point each).
    angles = linkage.home_theta[3] + np.linspace(0, 2 * np.pi, 720, endpoint=False)
    poses = linkage.link_poses(linkage.parameter_from_joint(angles, joint=3))
    points = {
        k: poses[k].act(np.array([0.03, 0.02, 0.01]) + 0.5 * (linkage.axes[k - 1].point + linkage.axes[k % 4].point))[
            :, None, :
        ]
        + noise * rng.normal(size=(720, 1, 3))
        for k in (1, 2, 3)
    }
    loop = identify_record(LinkRecord(np.arange(720) / 100.0, points, "noisy"), window=1).loop
    print("geometric method (720 frames, one point per link):")
    for i in range(4):
        print(
            f"  a{i} error {1e3 * (loop.dh.a[i] - linkage.a[i]):+.4f} mm, alpha{i} error "
            f"{np.degrees(loop.dh.alpha[i] - linkage.alpha[i]):+.4f} deg, d{i} {1e3 * loop.dh.d[i]:+.4f} mm"
        )


if __name__ == "__main__":
    main()
