"""Every class of bad scene-file input gets a one-line SceneError naming the key, where it is and the fix.

Each case edits the valid bar-pendulum scene of ``scene_fixtures`` by one text replacement; the
schema refuses it before any body is built, so the cases are cheap."""

import re

import pytest
from scene_fixtures import PENDULUM, write_bar, write_tet_matrices

from ffrf.errors import FEInputError, MaterialError, MeshError, SceneError
from ffrf.scenes.scene_file import load_scene

#: A valid spring-damper entry, edited by the force cases below.
SPRING = (
    '[[forces]]\nname = "support"\ntype = "spring_damper"\nbody0 = "ground"\nbody1 = "bar"\ninterface1 = "hinge"\n'
    "stiffness = [1e3]\n"
)


def _with_force(text: str) -> str:
    return text + "\n[[sensors]]"


#: The bar's mesh, material and order: what a body from matrices says instead.
MESH_BODY = 'mesh = "bar.vtu"\nunit = "mm"\nmaterial = {E = 1e8, nu = 0.3, rho = 450.0}\norder = 1\n'
NPZ = 'matrices = {format = "npz", file = "bar.npz"}\n'


CASES = {
    # class: (replace this, by this, expected words in the message)
    "stability of a dynamic run": (
        "rho_inf = 0.8",
        "rho_inf = 0.8\nstability = true",
        ["scene.toml, scene", "stability is judged at equilibria", 'set mode = "quasi_static"'],
    ),
    "unknown force type": (
        "[[sensors]]",
        _with_force(SPRING.replace("spring_damper", "sprung")),
        ["forces[0] 'support'", "'type' must be one of ['spring_damper', 'spring', 'load', 'motor']"],
    ),
    "spring to the ground without its point": (
        "[[sensors]]",
        _with_force(SPRING.replace("spring_damper", "spring")),
        ["a spring to the ground needs point0 = [x, y, z]"],
    ),
    "spring-damper without stiffness": (
        "[[sensors]]",
        _with_force(SPRING.replace("stiffness = [1e3]\n", "")),
        ["a spring_damper needs stiffness"],
    ),
    "spring-damper stiffness count": (
        "[[sensors]]",
        _with_force(SPRING.replace("[1e3]", "[1e3, 1e3]")),
        ["stiffness needs one value or 3 (one per elastic equation), got 2"],
    ),
    "key of another force type": (
        "[[sensors]]",
        _with_force(SPRING + "stall_torque = 1.0\n"),
        ["a spring_damper takes no ['stall_torque']"],
    ),
    "load without force or torque": (
        "[[sensors]]",
        _with_force('[[forces]]\nname = "push"\ntype = "load"\nbody = "bar"\ninterface = "hinge"\n'),
        ["a load needs force = [fx, fy, fz] (N), torque = [mx, my, mz] (N m) or both"],
    ),
    "load on an unknown interface": (
        "[[sensors]]",
        _with_force('[[forces]]\nname = "push"\ntype = "load"\nbody = "bar"\ninterface = "tip"\nforce = [1, 0, 0]\n'),
        ["body 'bar' has no interface 'tip'", "it has ['hinge']"],
    ),
    "motor without its curve": (
        "[[sensors]]",
        _with_force(
            '[[forces]]\nname = "m"\ntype = "motor"\nbody0 = "ground"\nbody1 = "bar"\ninterface1 = "hinge"\n'
            "stall_torque = 1.0\n"
        ),
        ["a motor needs stall_torque (N m) and no_load_speed (rad/s)"],
    ),
    "element size for a volume mesh": (
        'mesh = "bar.vtu"',
        'mesh = "bar.vtu"\nh = 0.01',
        ["'h' sizes the tetrahedra that fill an STL surface"],
    ),
    "unknown table": ("[[sensors]]", "[[sensor]]", ["unknown key 'sensor'", "did you mean 'sensors'"]),
    "misspelt setting": ("gravity =", "gravty =", ["scene.toml, scene", "'gravty'", "did you mean 'gravity'"]),
    "misspelt drive key": (
        'type = "revolute"',
        'type = "driven_revolute"\ndrive = {rpmm = 1.0}',
        ["joints[0] 'hinge', drive", "'rpmm'", "did you mean 'rpm'"],
    ),
    "string for a number": ("t_end = 0.1", 't_end = "0.1"', ["'t_end' must be a number", "'0.1'"]),
    "boolean for a number": ("step = 1e-3", "step = true", ["'step' must be a number"]),
    "nan": ("step = 1e-3", "step = nan", ["'step' must be finite"]),
    "infinite gravity": ("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, -inf]", ["'gravity' must be finite"]),
    "vector of wrong length": (
        "gravity = [0.0, 0.0, -9.81]",
        "gravity = [0.0, -9.81]",
        ["'gravity' must be a list of 3 numbers"],
    ),
    "zero step": ("step = 1e-3", "step = 0.0", ["'step' must be > 0"]),
    "negative end time": ("t_end = 0.1", "t_end = -1.0", ["'t_end' must be > 0"]),
    "too few outputs": ("outputs = 101", "outputs = 1", ["'outputs' must lie in [2, 1e+06]"]),
    "run too long": ("t_end = 0.1", "t_end = 1e5", ["1e+08 time steps", "check the units", "12.2 h at 0.44 ms"]),
    "rho_inf out of range": ("rho_inf = 0.8", "rho_inf = 1.5", ["'rho_inf' must lie in [0, 1]"]),
    "unknown mode": ('mode = "dynamic"', 'mode = "static"', ["'mode' must be one of", "quasi_static"]),
    "negative Young's modulus": ("E = 1e8", "E = -1e8", ["bodies[0] 'bar', material", "'E' must be > 0"]),
    "zero density": ("rho = 450.0", "rho = 0.0", ["'rho' must be > 0"]),
    "Poisson ratio 0.5": ("nu = 0.3", "nu = 0.5", ["'nu' must lie in (-1, 0.5)"]),
    "missing material": ("material = {E = 1e8, nu = 0.3, rho = 450.0}\n", "", ["missing required key 'material'"]),
    "unknown unit": ('unit = "mm"', 'unit = "inch"', ["'unit' must be one of ['m', 'mm']"]),
    "element order 3": ("order = 1", "order = 3", ["'order' must be one of [1, 2]"]),
    "negative mode count": ("modes = 3", "modes = -1", ["'modes' must be >= 0"]),
    "no interface": (
        'interfaces = [{name = "hinge", nodes_file = "hinge.txt"}]',
        "interfaces = []",
        ["list at least one interface"],
    ),
    "two selectors": (
        'nodes_file = "hinge.txt"}',
        'nodes_file = "hinge.txt", group = "end"}',
        ["exactly one of group, cylinder, axis, plane or nodes_file"],
    ),
    "mesh and matrices": (
        'mesh = "bar.vtu"',
        'mesh = "bar.vtu"\nmatrices = {format = "npz", file = "bar.npz"}',
        ['give exactly one of mesh = "file", parametric', "or matrices", "got ['mesh', 'matrices']"],
    ),
    "mesh keys on a body from matrices": (
        'mesh = "bar.vtu"\nunit = "mm"\n',
        NPZ,
        ["['material', 'order'] describe a mesh; a body from matrices takes its mass and stiffness from its files"],
    ),
    "missing matrix file": (MESH_BODY, NPZ, ["matrices: file = 'bar.npz'", "not found; give a path relative to"]),
    "files of another matrix format": (
        MESH_BODY,
        'matrices = {format = "npz", file = "bar.npz", mass = "M.mtx"}\n',
        ["matrices: format = 'npz' reads file = ... (not ['mass'])"],
    ),
    "matrix sizes disagree": (
        MESH_BODY,
        'matrices = {format = "matrix_market", nodes = "tri_nodes.txt", mass = "tet_M.mtx", stiffness = "tet_K.mtx"}\n',
        ["body 'bar', matrices:", "tet_M.mtx: the matrix is 12 x 12, expected 9 x 9 (3 DOFs per node)"],
    ),
    "group interface on a body from matrices": (
        MESH_BODY + 'modes = 3\ninterfaces = [{name = "hinge", nodes_file = "hinge.txt"}]',
        NPZ + 'modes = 3\ninterfaces = [{name = "hinge", group = "end"}]',
        ["select it by exactly one of cylinder, plane or nodes_file, got ['group']; a body from matrices has no named"],
    ),
    "unknown reduction": (
        "modes = 3",
        'modes = 3\nreduction = "guyan"',
        ["'reduction' must be one of ['craig_bampton', 'free_free'], got 'guyan'"],
    ),
    "free-free body without modes": (
        "modes = 3",
        'modes = 0\nreduction = "free_free"',
        ['reduction = "free_free" keeps modes >= 1 flexible free-free modes, got 0', "give modes >= 1"],
    ),
    "zero joint axis": ("axis = [0.0, 1.0, 0.0]", "axis = [0.0, 0.0, 0.0]", ["'axis' has zero length"]),
    "joint axis of length 1e-300": (  # its square underflows to 0: a nan direction and a traceback in the run
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1e-300, 0.0]",
        ["'axis' has length 1e-300, too short to give a direction"],
    ),
    "step longer than the run": (
        "step = 1e-3",
        "step = 1.0",
        ["step = 1.0 s is longer than the run, t_end = 0.1 s; give step <= t_end"],
    ),
    "run too long for its limit": (
        "rho_inf = 0.8",
        "rho_inf = 0.8\nmax_steps = 10",  # t_end / step = 100 steps
        ["100 time steps (t_end / step) (more than 10", "set max_steps = N in [scene] to run it anyway"],
    ),
    "one side's axis and the common axis": (
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 1.0, 0.0]\naxis1 = [0.0, 1.0, 0.0]",
        ["give either axis/point (both sides) or axis1/point1 (side 1), not both"],
    ),
    "drive speed twice": (
        'type = "revolute"',
        'type = "driven_revolute"\ndrive = {rpm = 1.0, omega = 0.1}',
        ["drive: give exactly one of rpm", "omega = ... (rad/s)"],
    ),
    "start pose not a rotation": (
        "modes = 3",
        "modes = 3\npose = {euler_parameters = [1.0, 0.1, 0.0, 0.0]}",
        ["'euler_parameters' must have unit length", "norm 1.00499"],
    ),
    "unknown joint type": ('type = "revolute"', 'type = "prismatic"', ["'type' must be one of", "driven_revolute"]),
    "drive on a plain revolute": (
        'type = "revolute"',
        'type = "revolute"\ndrive = {rpm = 1.0}',
        ["a revolute joint has no drive"],
    ),
    "driven joint without drive": ('type = "revolute"', 'type = "driven_revolute"', ["needs drive = {rpm"]),
    "zero drive speed": ('type = "revolute"', 'type = "driven_revolute"\ndrive = {rpm = 0.0}', ["'rpm' must not be 0"]),
    "drive start angle of 1e300 deg": (
        'type = "revolute"',
        'type = "driven_revolute"\ndrive = {rpm = 1.0, start_angle_deg = 1e300}',
        ["drive: 'start_angle_deg' must lie in [-360, 360], got 1e+300"],
    ),
    "unknown body in a joint": ('body1 = "bar"', 'body1 = "rod"', ["unknown body 'rod'", "bodies are ['bar']"]),
    "unknown interface": ('interface1 = "hinge"', 'interface1 = "bore"', ["no interface 'bore'", "['hinge']"]),
    "duplicate body names": (
        "[[joints]]",
        '[[bodies]]\nname = "bar"\nmesh = "bar.vtu"\nmaterial = {E = 1e8, '
        'nu = 0.3, rho = 450.0}\ninterfaces = [{name = "a", group = "g"}]\n[[joints]]',
        ["two bodies are named 'bar'"],
    ),
    "sensor on an unknown body": (
        'body = "bar"\npoint',
        'body = "beam"\npoint',
        ["sensors[0] 'tip'", "unknown body 'beam'"],
    ),
    "sensor point and node": ("point = [0.2, 0.0, 0.0]", "point = [0.2, 0.0, 0.0]\nnode = 3", ["exactly one of point"]),
    "sensor on an unknown joint": (
        "point = [0.2, 0.0, 0.0]",
        'joints = ["hing"]',
        ["sensors[0] 'tip': unknown joint 'hing'; joints are ['hinge']"],
    ),
    "missing mesh file": ('mesh = "bar.vtu"', 'mesh = "missing.vtu"', ["missing.vtu not found"]),
    "not TOML": ("[scene]", "[scene", ["cannot read the scene"]),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_scene_is_refused_with_a_clear_message(tmp_path, case):
    old, new, words = CASES[case]
    assert PENDULUM.count(old) >= 1, "the case must edit the valid scene"
    write_bar(tmp_path)
    write_tet_matrices(tmp_path)
    (tmp_path / "scene.toml").write_text(PENDULUM.replace(old, new, 1))
    with pytest.raises(SceneError) as error:
        load_scene(tmp_path / "scene.toml")
    message = str(error.value)
    assert "\n" not in message
    for word in words:
        assert word in message, (word, message)


def test_sensor_point_off_the_body_is_refused(tmp_path):
    write_bar(tmp_path)
    (tmp_path / "scene.toml").write_text(PENDULUM.replace("point = [0.2, 0.0, 0.0]", "point = [0.2, 0.5, 0.0]"))
    with pytest.raises(SceneError, match=r"sensor 'tip': point .* is 0.4\d* m from the nearest node of body 'bar'"):
        load_scene(tmp_path / "scene.toml")


def test_material_is_checked_outside_scene_files_too():
    from ffrf.fe.materials import Material

    for arguments, words in [
        ((-1.0, 0.3, 1.0), "E"),
        ((1e9, 0.5, 1.0), "nu"),
        ((1e9, 0.3, 0.0), "rho"),
        ((float("nan"), 0.3, 1.0), "E"),
    ]:
        with pytest.raises(MaterialError, match=words):
            Material(*arguments, name="test")
    assert issubclass(SceneError, FEInputError) and issubclass(MaterialError, FEInputError)


def test_unreadable_mesh_file_is_a_mesh_error(tmp_path):
    """meshio exits the interpreter on some broken files; the scene gets a MeshError instead."""
    write_bar(tmp_path)
    (tmp_path / "bar.vtu").write_text("garbage")
    (tmp_path / "scene.toml").write_text(PENDULUM)
    with pytest.raises(MeshError, match="bar.vtu: meshio cannot read it"):
        load_scene(tmp_path / "scene.toml")


PARAMETRIC_BODY = {
    "name": "link",
    "material": {"E": 1.2e9, "nu": 0.33, "rho": 450.0},
    "interfaces": [{"name": "a", "group": "a"}],
}
AXIS_A = {"name": "a", "point": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0]}
AXIS_B = {"name": "b", "point": [0.1, 0.0, 0.0], "direction": [0.0, 1.0, 0.0]}
PARAMETRIC_CASES = {
    "link without axes": ({"h": 0.012}, "parametric: missing required key 'axes'"),
    "three axes on a link": ({"axes": [AXIS_A, AXIS_B, AXIS_B]}, "a link has exactly two axes, got 3"),
    "joint point off its axis": (
        {"axes": [dict(AXIS_A, joint_point=[0.0, 0.01, 0.0]), AXIS_B], "h": 0.012},
        "joint point [0.0, 0.01, 0.0] of interface 'a' is 0.01 m off its axis",
    ),
    "link design in millimetres": (
        {"axes": [AXIS_A, AXIS_B], "design": {"arm_width": 16.0}},
        "parametric design: LinkDesign.arm_width=16.0 m: suspicious units, did you pass millimetres?",
    ),
}


@pytest.mark.parametrize("case", sorted(PARAMETRIC_CASES))
def test_bad_parametric_link_is_refused(case):
    from ffrf.errors import GeometryError
    from ffrf.scenes.builder import build_scene

    spec, words = PARAMETRIC_CASES[case]
    with pytest.raises((SceneError, GeometryError), match=re.escape(words)):
        build_scene({"bodies": [dict(PARAMETRIC_BODY, parametric=spec)]})


def test_an_axis_on_the_surface_finds_no_bore():
    """``axis = {...}`` interface selection along an edge of a solid bar: no bore around it."""
    from body_fixtures import bar_model

    from ffrf.errors import InterfaceError
    from ffrf.fe.interfaces import interface_around_axis

    with pytest.raises(InterfaceError, match=r"interface 'pin' of .*touches the body's surface"):
        interface_around_axis(bar_model(), "pin", [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
