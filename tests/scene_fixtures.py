"""A scene file shared by the scene-file tests and the scene cross-validation: a flexible bar
(``body_fixtures.bar_model``) hinged at one end, swinging under gravity."""

import meshio
import numpy as np
from body_fixtures import bar_model

PENDULUM = """
[scene]
name = "bar pendulum"
gravity = [0.0, 0.0, -9.81]
mode = "dynamic"
t_end = 0.1
step = 1e-3
rho_inf = 0.8
outputs = 101

[[bodies]]
name = "bar"
mesh = "bar.vtu"
unit = "mm"
material = {E = 1e8, nu = 0.3, rho = 450.0}
modes = 3
interfaces = [{name = "hinge", nodes_file = "hinge.txt"}]

[[joints]]
name = "hinge"
type = "revolute"
body0 = "ground"
body1 = "bar"
interface1 = "hinge"
axis = [0.0, 1.0, 0.0]

[[sensors]]
name = "tip"
body = "bar"
point = [0.2, 0.0, 0.0]
"""


def write_bar(tmp_path):
    model = bar_model(E=1e8, rho=450.0)
    meshio.write(tmp_path / "bar.vtu", meshio.Mesh(1e3 * model.mesh.points, [("tetra", model.mesh.tets)]))
    np.savetxt(tmp_path / "hinge.txt", np.flatnonzero(model.nodes[:, 0] < 1e-9), fmt="%d")
    return model
