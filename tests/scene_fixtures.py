"""Scene files shared by the scene-file tests and the scene cross-validation: a flexible bar
(``body_fixtures.bar_model``) hinged at one end, swinging under gravity, and the paper's
parametric link 1 turned by a motor at its first bore."""

import meshio
import numpy as np
from body_fixtures import bar_model

#: The paper's Bennett linkage as a linkage file (mm), coarse, joint 3 driven from -90 deg, link 2 the coupler.
COARSE_BENNETT_FILE = """[linkage]
dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}
unit = "mm"
driver = 3
tool_link = 2
start_angle_deg = -90.0
h = 0.012
order = 1
modes = 2
"""

#: The coarse Bennett with 0.1 mm of play in its passive joints (12 mm pins), 18 deg of drive, 5 outputs.
LOOSE_BENNETT_FILE = (
    COARSE_BENNETT_FILE
    + """revolutions = 0.05
check_clearance = false

[scene]
mode = "quasi_static"
outputs = 5
clearance = {radial_mm = 0.1, pin_length_mm = 12.0}
"""
)

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
order = 1
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


def write_tet_matrices(tmp_path):
    """Files of a model that does not fit together: M and K of 4 nodes (12 x 12), a node table of 3."""
    import scipy.io
    import scipy.sparse as sp

    for name in ("tet_M.mtx", "tet_K.mtx"):
        scipy.io.mmwrite(tmp_path / name, sp.identity(12, format="coo"))
    np.savetxt(tmp_path / "tri_nodes.txt", np.eye(3))


def paper_link_axes_toml(link: int) -> str:
    """The two axes of the paper's link ``link`` (:func:`ffrf.paper.axes.paper_link_axes`) as a scene file's
    ``axes = [...]`` of a parametric link (TOML text; floats written exactly)."""
    from ffrf.paper.axes import bennett_axes, paper_link_axes

    first, second, names = paper_link_axes(link, bennett_axes(90.0))
    return (
        "["
        + ", ".join(
            f'{{name = "{name}", point = {axis.point.tolist()}, direction = {axis.direction.tolist()}}}'
            for axis, name in ((first, names[0]), (second, names[1]))
        )
        + "]"
    )


def driven_link_scene(axis: str, t_end: float, outputs: int, modes: int, sensor: bool = False) -> str:
    """Quasi-static parametric PLA link 1 of the paper driven at its first bore about ``axis`` (TOML list text)."""
    text = f"""
[scene]
name = "driven link"
mode = "quasi_static"
t_end = {t_end}
outputs = {outputs}
beta = 0.005
[[bodies]]
name = "link1"
parametric = {{axes = {paper_link_axes_toml(1)}, h = 0.008}}
material = {{E = 1.2e9, nu = 0.33, rho = 450.0}}
order = 1
modes = {modes}
interfaces = [{{name = "a", group = "joint0"}}, {{name = "b", group = "joint1"}}]
[[joints]]
name = "motor"
type = "driven_revolute"
body0 = "ground"
body1 = "link1"
interface1 = "a"
axis = {axis}
point = [0.0, 0.0, 0.0085]
drive = {{rpm = 1.0, ramp_time = 1.0}}
"""
    if sensor:
        text += """[[sensors]]
name = "far_bore"
body = "link1"
point = [-0.11, 0.0, 0.0]               # the second bore (joint1) of link 1
"""
    return text
