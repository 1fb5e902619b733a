"""The paper's motivation for the geometric method: a direct fit of all DH parameters to the
coupler path is ill-conditioned near a Bennett linkage."""

import numpy as np

from identification.naive_fit import naive_path_jacobian
from kinematics import BennettLinkage


def test_naive_path_fit_is_ill_conditioned():
    linkage = BennettLinkage.paper()
    parameters = np.r_[linkage.a, linkage.alpha, np.zeros(4), [0.05, 0.03, 0.02]]
    jacobian = naive_path_jacobian(parameters, n_angles=24)
    # A well-posed fit of 15 parameters to 72 coordinates would have singular values of similar size;
    # here the weakest direction is seven orders of magnitude below the strongest.
    assert jacobian.condition_number > 1e6
    assert len(jacobian.describe()) == 3
