"""Guards of issue #32, "no silent wrong answer": command-line flags checked like file keys, sizes refused with
their estimate and the key that lifts the limit, files that used to end in a traceback (a NaN node, a text file
as a mesh, a Vicon cell of 1e300), a UTF-8 byte-order mark, and plausibility warnings (a bore error given twice,
lengths in the wrong unit). Every refusal happens before anything is built, so no test compiles a kernel.

The expected numbers are counted by hand from the inputs (a 1 s ramp and one revolution at 1 rpm last 61 s;
1e6 revolutions at 3 deg per equilibrium are 1.2e8 equilibria), never read from the code's output."""

import math
import tomllib
import warnings

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scene_fixtures import PENDULUM, write_bar
from test_cli_numbers_and_files import one_line_error, tiny_vicon_csv
from test_linkage_input import GOOD as LINKAGE
from test_study_input import GOOD as STUDY
from test_study_input import GRID_1000_BY_1000

from ffrf.cli import main
from ffrf.errors import FEInputError, MeshError, SceneError
from ffrf.mesh.tet_mesh import TetMesh, read_mesh
from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.scene_file import load_scene
from ffrf.scenes.scene_schema import check_scene
from ffrf.studies.spec import design_size, load_study, study_from_document

BOM = b"\xef\xbb\xbf"


def _usage_error(capsys, argv: list[str]) -> str:
    """The argparse error line of ``python -m ffrf argv`` (exit status 2)."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


#: case -> (arguments after the command, the flag's error)
FLAG_CASES = {
    "no outputs": (["bennett", "--outputs", "0"], "argument --outputs: must be a whole number >= 2, got '0'"),
    "outputs above the limit": (
        ["bennett", "--outputs", "2000000"],
        "argument --outputs: must be a whole number <= 1e+06, got '2000000'",
    ),
    "negative time step": (["bennett", "--dt", "-1"], "argument --dt: must be a finite number > 0 s, got '-1'"),
    "infinite time step": (["bennett", "--dt", "inf"], "argument --dt: must be a finite number > 0 s, got 'inf'"),
    "nan time step": (["bennett", "--dt", "nan"], "argument --dt: must be a finite number > 0 s, got 'nan'"),
    "negative ParaView interval": (
        ["bennett", "--vtk-every", "-1"],
        "argument --vtk-every: must be a whole number >= 0, got '-1'",
    ),
    "no modes on the command line": (["bennett", "--modes", "0"], "argument --modes: must be a whole number >= 1"),
    "element edge of 1e300 m": (
        ["bennett", "--h", "1e300"],
        "argument --h: must be a finite number in [0.0005, 0.05] m, got '1e300'",
    ),
    "zero model scale": (
        ["linkage", "--model", "bennett_ark24", "--scale", "0"],
        "argument --scale: must be a finite number > 0, got '0'",
    ),
    "negative driver": (
        ["linkage", "--model", "bennett_ark24", "--driver", "-1"],
        "argument --driver: must be a whole number >= 0",
    ),
    "no steps allowed": (["bennett", "--max-steps", "0"], "argument --max-steps: must be a whole number >= 1"),
    "two placements of the links": (
        ["linkage", "--model", "bennett_ark24", "--design-points", "--collision-free"],
        "argument --collision-free: not allowed with argument --design-points",
    ),
}


@pytest.mark.parametrize("case", FLAG_CASES)
def test_every_run_flag_is_checked_like_a_file_key(tmp_path, capsys, case):
    arguments, words = FLAG_CASES[case]
    line = _usage_error(capsys, [*arguments, "--out", str(tmp_path / "out")])
    assert words in line, line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", [["bennett"], ["linkage", "--model", "bennett_ark24"]], ids=["bennett", "linkage"])
@pytest.mark.parametrize("mode", [["--dynamic"], []], ids=["dynamic", "auto"])
def test_a_nanosecond_step_is_refused_with_its_estimate_before_building(tmp_path, capsys, command, mode):
    """Once an AttributeError on the error path: 61 s of drive (1 s ramp, one revolution at 1 rpm) in 1e-9 s steps.
    With the mode left to the run (auto), a step given counts: it is there to be used."""
    out = tmp_path / "out"
    assert main([*command, *mode, "--dt", "1e-9", "--out", str(out)]) == 2
    err = one_line_error(capsys)
    assert "6.1e+10 time steps over the revolution (more than 1e+07" in err, err
    assert "at least 311 days at 0.44 ms per step" in err and "set --max-steps N to run it anyway" in err, err
    assert not out.exists()


def test_a_bore_error_of_1e300_deg_on_the_command_line_is_one_line_before_the_output_folder(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["linkage", "--model", "bennett_ark24", "--bore-error", "3:0:1e300", "--out", str(out)]) == 2
    assert "bore_errors[0]: 'twist_deg' must lie in [-180, 180], got 1e+300" in one_line_error(capsys)
    assert not out.exists()


def test_max_steps_lifts_the_limit_of_the_command_line(tmp_path, capsys, monkeypatch):
    import ffrf.cli.bennett as bennett_command

    def built(*args, **kwargs):
        raise SceneError("the scene would be built now")

    monkeypatch.setattr(bennett_command, "build_bennett", built)
    argv = ["bennett", "--dynamic", "--dt", "1e-9", "--max-steps", "100000000000", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "error: the scene would be built now" in capsys.readouterr().err


def test_a_run_that_stops_at_its_first_step_is_reported_not_an_attribute_error(monkeypatch):
    """With the step limit lifted, a 1e-9 s step's Newton fails at once; the solver's partial run of one output is no
    LinkageResult, and the command line read its metadata (AttributeError). Now no partial result: "the run stopped"."""
    from types import SimpleNamespace

    import ffrf.scenes.linkage_run as linkage_run
    from ffrf.errors import NewtonDivergence
    from ffrf.solvers.simulate import Run

    def stops(*args, **kwargs):
        raise NewtonDivergence("Newton did not converge at t = 1e-09 s", Run(np.zeros(1), np.zeros((1, 3)), None, []))

    monkeypatch.setattr(linkage_run, "choose_mode", lambda scene: ("dynamic", 1.0))
    monkeypatch.setattr(linkage_run, "assemble", lambda scene: SimpleNamespace(q=np.zeros(3), multipliers=None))
    monkeypatch.setattr(linkage_run, "scene_assembly_stress", lambda *args: None)
    monkeypatch.setattr(linkage_run, "quasi_static_step", lambda scene: None)
    for rule in ("quasi_static_path_step", "dynamic_step_limit", "near_dead_point"):  # no loop in this stand-in
        monkeypatch.setattr(linkage_run, rule, lambda *args: None)
    monkeypatch.setattr(linkage_run, "dynamic_error_tolerance", lambda scene: 1e-6)
    monkeypatch.setattr(linkage_run, "simulate", stops)
    with pytest.raises(NewtonDivergence, match="did not converge") as stopped:
        linkage_run.run_linkage(SimpleNamespace(t_end=61.0, system=None), mode="dynamic", step=1e-9)
    assert stopped.value.partial is None


def test_size_limits_are_lifted_by_their_keys(tmp_path):
    """The keys that the refusals name (max_steps in [scene], max_variants in [study]) lift the limits."""
    long = LINKAGE.replace("driver = 3", "driver = 3\nrevolutions = 1e6") + "[scene]\nmax_steps = 1e9\n"
    _, options, _ = linkage_options(tomllib.loads(long))
    assert options.revolutions == 1e6
    scene = tomllib.loads(PENDULUM.replace("t_end = 0.1", "t_end = 1e5").replace("rho_inf", "max_steps = 1e9\nrho_inf"))
    check_scene(scene)  # 1e8 steps, below the lifted limit
    lifted = GRID_1000_BY_1000.replace("\n\n[base]", "\nmax_variants = 1000000\n\n[base]")
    grid = STUDY[: STUDY.index('method = "sobol"')] + lifted
    study = study_from_document(tomllib.loads(grid), bases=STUDY_BASES)
    assert design_size(study.method, study.samples, study.parameters) == 1000 * 1000


@pytest.mark.parametrize("kind", ["scene", "linkage", "study"])
def test_a_byte_order_mark_is_read_as_the_text_it_precedes(tmp_path, kind):
    """Windows editors write a UTF-8 BOM; once 'Invalid statement (line 1, col 1)', now the file's own first error."""
    text, load, words = {
        "scene": (PENDULUM.replace("gravity", "gravty"), load_scene, "did you mean 'gravity'"),
        "linkage": (LINKAGE.replace("driver", "drver"), load_scene, "did you mean 'driver'"),
        "study": (
            STUDY.replace('"sobol"', '"random"'),
            lambda path: load_study(path, STUDY_BASES),
            "'method' must be one of",
        ),
    }[kind]
    (tmp_path / "file.toml").write_bytes(BOM + text.encode())
    with pytest.raises(SceneError, match=words):
        load(tmp_path / "file.toml")


def test_a_valid_study_with_a_byte_order_mark_loads(tmp_path):
    (tmp_path / "study.toml").write_bytes(BOM + STUDY.encode())
    assert load_study(tmp_path / "study.toml", bases=STUDY_BASES).samples == 8


def test_a_nan_node_coordinate_is_a_mesh_error(tmp_path):
    """Once a RuntimeError of scikit-fem ('reordered the mesh points') far from the cause."""
    points = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, np.nan, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(MeshError, match=r"1 points have coordinates that are not finite, first point 2 at \[0.0, nan"):
        TetMesh(points, np.array([[0, 1, 2, 3]]))
    meshio.write(tmp_path / "nan.vtu", meshio.Mesh(points, [("tetra", np.array([[0, 1, 2, 3]]))]))
    with pytest.raises(MeshError, match="nan.vtu: 1 points have coordinates that are not finite"):
        read_mesh(tmp_path / "nan.vtu")


def test_a_text_file_given_as_a_mesh_is_one_line(tmp_path, capsys):
    """meshio printed its own 'Error: Couldn't read file' line before ours (and exited)."""
    write_bar(tmp_path)
    (tmp_path / "bar.vtu").write_text("a list of points\n1 2 3\n")
    (tmp_path / "scene.toml").write_text(PENDULUM)
    assert main(["run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")]) == 2
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and len(captured.err.strip().splitlines()) == 1, captured.err
    assert "bar.vtu: meshio cannot read it (Error: Couldn't read file" in captured.err
    assert captured.out == ""


@pytest.mark.parametrize(
    "cell, words",
    [
        ("1e300", "segment 'Bennett:Link1' is 1e+297 m from the origin (more than 1000 m"),
        ("inf", "line 6, column 6: 'inf' is not a finite number; a missing frame is an empty cell"),
        ("1e400", "'1e400' is not a finite number"),
    ],
)
def test_a_vicon_cell_out_of_any_capture_volume_is_refused(tmp_path, capsys, cell, words):
    from identification.__main__ import main as identify

    lines = tiny_vicon_csv().splitlines()
    cells = lines[5].split(",")
    cells[5] = cell  # link 1's TX in the first data row (line 6)
    lines[5] = ",".join(cells)
    (tmp_path / "run.csv").write_text("\n".join(lines) + "\n")
    assert identify(["--vicon", str(tmp_path / "run.csv")]) == 2
    assert words in one_line_error(capsys)


def test_duplicate_bore_errors_warn_that_they_add_up():
    twice = "bore_errors = [{joint = 3, link = 0, twist_deg = 1.0}, {joint = 0, link = 0}, {joint = 3, link = 0}]"
    document = tomllib.loads(LINKAGE.replace("driver = 3", "driver = 3\n" + twice))
    with pytest.warns(UserWarning, match=r"bore_errors\[0\] and bore_errors\[2\] both set the bore of joint 3 on l"):
        linkage_options(document)
    once = tomllib.loads(LINKAGE.replace("driver = 3", "driver = 3\n" + twice.replace(", {joint = 3, link = 0}", "")))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # two different bores of link 0: no warning
        linkage_options(once)


@pytest.mark.parametrize(
    "dh, unit, words",
    [
        ("a = [110, 220, 110, 220]", "", "the longest link is 220 m, above 10 m: lengths in millimetres read as"),
        ("a = [0.11, 0.22, 0.11, 0.22]", 'unit = "mm"', "the longest link is 0.22 mm, below 1 mm: lengths in metres"),
    ],
    ids=["millimetres as metres", "metres as millimetres"],
)
def test_linkage_lengths_in_the_wrong_unit_warn(dh, unit, words):
    text = LINKAGE.replace("a = [110, 220, 110, 220]", dh).replace('unit = "mm"', unit)
    with pytest.warns(UserWarning, match=words):
        linkage_options(tomllib.loads(text))


def test_a_model_scaled_by_a_factor_of_millimetres_warns():
    """Rational Linkages' models are of unit size (scale 0.1 gives links of a few cm); scale = 100 gives links of
    tens of metres."""
    with pytest.warns(UserWarning, match=r"above 10 m: .*check scale = 100"):
        linkage_options({"linkage": {"model": "bennett_ark24", "scale": 100}})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        linkage_options({"linkage": {"model": "bennett_ark24"}})


@pytest.mark.parametrize("factor, words", [(1e-3, "0.22 mm, below 1 mm"), (1e3, "220 m, above 10 m")])
def test_identification_in_the_wrong_unit_warns(factor, words):
    """The paper's Bennett linkage (links of 110 and 220 mm) tracked in metres read as millimetres, and back."""
    from identification import LinkRecord, identify_record
    from kinematics import BennettLinkage

    linkage = BennettLinkage.paper()
    angles = np.linspace(0.0, 2.0 * np.pi, 120, endpoint=False)
    t = linkage.parameter_from_joint(linkage.home_theta[3] + angles, joint=3)
    poses = linkage.link_poses(t)
    points = {}
    for link in (1, 2, 3):
        middle = 0.5 * (linkage.axes[link - 1].point + linkage.axes[link % 4].point) + 0.01
        points[link] = factor * np.stack([poses[link].act(middle)], axis=1)
    assert max(linkage.a) == pytest.approx(0.22)
    with pytest.warns(UserWarning, match=words):
        identify_record(LinkRecord(np.arange(len(angles)) / 100.0, points, "run.csv"), window=1)


# -- properties: whatever the number, one of our errors or a value in range, never a traceback ---------------------

NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, 1e-9, 1e9, 0.5, -1.0]),
    st.integers(-(10**13), 10**13),
)


@settings(
    max_examples=120, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    flag=st.sampled_from(["--dt", "--outputs", "--vtk-every", "--modes", "--h", "--max-steps", "--driver", "--scale"]),
    value=NUMBERS,
)
def test_any_number_on_a_run_flag_is_a_usage_error_or_in_range(tmp_path, capsys, monkeypatch, flag, value):
    """A flag's value is refused by argparse (exit 2, one ``argument --flag`` line) or reaches the run in range."""
    import ffrf.cli as cli

    seen = {}

    def record(args):
        seen.update(vars(args))
        return 0

    monkeypatch.setitem(cli.SUBCOMMANDS, "linkage", (*cli.SUBCOMMANDS["linkage"][:2], record))
    text = repr(value)
    try:
        status = main(["linkage", "--model", "bennett_ark24", f"{flag}={text}", "--out", str(tmp_path / "o")])
    except SystemExit as exit_:
        assert exit_.code == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert f"argument {flag}:" in err and text in err, err
        return
    assert status == 0
    got = seen[flag[2:].replace("-", "_")]
    assert math.isfinite(got)
    low = {"--dt": 0.0, "--outputs": 2, "--vtk-every": 0, "--modes": 1, "--h": 5e-4, "--max-steps": 1}
    assert got >= low.get(flag, 0) and (flag not in ("--dt", "--scale") or got > 0)


LINKAGE_NUMBER_KEYS = ("revolutions", "start_angle_deg", "modes", "h", "scale", "twist_deg", "offset", "step")


@settings(max_examples=120, deadline=None, derandomize=True)
@given(key=st.sampled_from(LINKAGE_NUMBER_KEYS), value=NUMBERS)
def test_any_number_in_a_linkage_file_is_refused_in_one_line_or_taken(key, value):
    """Whatever number a linkage file's key holds, checking it (before any build) ends in a one-line SceneError or
    gives options whose run is within the step limit; never a traceback, never minutes of silence."""
    text = LINKAGE
    if key in ("twist_deg", "offset"):
        text = text.replace("driver = 3", f"driver = 3\nbore_errors = [{{joint = 3, link = 0, {key} = {value!r}}}]")
    elif key == "step":
        text += f'[scene]\nmode = "dynamic"\nstep = {value!r}\n'
    else:
        text = text.replace("driver = 3", f"driver = 3\n{key} = {value!r}")
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return  # e.g. a Python repr that is no TOML number
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # plausibility warnings are not refusals
        try:
            _, options, run = linkage_options(document)
        except FEInputError as error:
            assert "\n" not in str(error)
            return
    # taken: at most 1e7 equilibria of 3 deg (120 per revolution), a start within a turn
    assert options.revolutions * 120 <= 1e7 and abs(options.start_angle) <= 2 * math.pi


@settings(max_examples=150, deadline=None, derandomize=True)
@given(
    method=st.sampled_from(["monte_carlo", "lhs", "sobol", "saltelli"]),
    samples=st.one_of(st.integers(-5, 10**6), st.sampled_from([2**k for k in (10, 16, 17, 20, 30, 40)])),
)
def test_any_sample_count_is_refused_in_one_line_or_within_the_limit(method, samples):
    """Whatever the sample count, a study file is refused in one line before any worker, or its design, counted by
    hand (N, or N (d + 2) for Saltelli with d = 1), has at most 1e5 variants."""
    text = STUDY.replace('method = "sobol"', f'method = "{method}"').replace("samples = 8", f"samples = {samples}")
    try:
        study = study_from_document(tomllib.loads(text), bases=STUDY_BASES)
    except SceneError as error:
        assert "\n" not in str(error)
        return
    assert (samples * 3 if method == "saltelli" else samples) <= 100_000
    assert design_size(study.method, study.samples, study.parameters) <= 100_000
