"""Example 1: the paper's Bennett linkage from its DH table
========================================================

Problem: given a = (110, 220, 110, 220) mm and alpha = (150, 90, 150, 90) deg, find the joint
axes, the configuration curve and the coupler's motion polynomial, and check that the DH chain
closes all along the motion. The paper's answer: (t0, t1, t2, t3) = (t, sqrt3 t, -t, -sqrt3 t).
"""

import numpy as np

from kinematics import BennettLinkage


def main() -> float:
    bennett = BennettLinkage.paper()
    for i, axis in enumerate(bennett.axes):
        print(f"h{i}: direction {np.round(axis.direction, 4)}, point {np.round(1e3 * axis.point, 3)} mm")
    ratio = bennett.coefficients[1]
    print(f"configuration curve: t1 = {ratio:.12f} t  (sqrt 3 = {np.sqrt(3):.12f})")
    residual = bennett.closure_residual(np.tan(np.linspace(-1.5, 1.5, 101)))
    print(f"largest closure residual along the motion: {residual.translation.max():.1e} m")
    return float(ratio)


if __name__ == "__main__":
    main()
