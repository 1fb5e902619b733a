"""Our twins of Exudyn's TestModels with modal flexible bodies (``python -m validation testmodels``).

Truth: the numbers Exudyn stores for its regression scripts (``runTestSuiteRefSol.py`` at commit
e44aca1b), and Exudyn 1.13.6 running the same scripts (rebuilt with its own items and FE helpers).
Each model: ours within 1e-9 of the stored value (NGsolveCMStest: within 1e-11 of Exudyn's converged
run, which is as far from the stored value as ours), ours against Exudyn's runs within 100 times the
largest difference measured (2026-11-24, AMD EPYC, 5 runs of Exudyn per model: its sparse eigensolver
returns another basis of the same span each run). objectFFRFTest2 takes about 110 s (our body has
339 modes; most of the time is its complex-step Jacobian): marked slow.
"""

from __future__ import annotations

import dataclasses
import json
import pickle
from functools import cache

import numpy as np
import pytest

from validation.__main__ import main
from validation.testmodels import TESTMODELS, model_named
from validation.testmodels import report as testmodels_report
from validation.testmodels.fe_data import DATA, NETGEN_PICKLE_BLOB, netgen_model, read_fem_pickle
from validation.testmodels.rotor_springs import FFRF_TEST2, tisserand_basis
from validation.testmodels.spec import CONVERGED_TOLERANCE, STORED_TOLERANCE, judge, relative

#: name -> largest measured (ours vs Exudyn at the script's settings, ours vs Exudyn converged) over 5
#: runs of Exudyn (3 of abaqusImportTest, 1 of objectFFRFTest2, 24 converged runs of
#: objectFFRFreducedOrderTest, whose results scatter by up to 4.5e-12); the tests allow 100 times these,
#: the converged ones at most 1e-11.
MEASURED = {
    "objectFFRFreducedOrderTest": (1.7e-10, 4.5e-12),
    "superElementRigidJointTest": (1.6e-11, 1.7e-14),
    "abaqusImportTest": (1.3e-13, 1.3e-13),
    "NGsolveCMStest": (1.24e-9, 9.0e-13),
    "objectFFRFreducedOrderAccelerations": (8.1e-12, 3.1e-13),
    "objectFFRFTest2": (6.1e-10, 7.8e-15),
}


@cache
def evaluated(name: str) -> dict:
    return testmodels_report.evaluate(model_named(name))


def _params():
    return [pytest.param(m.name, marks=pytest.mark.slow) if m.slow else m.name for m in TESTMODELS]


@pytest.mark.parametrize("name", _params())
def test_ours_meets_the_stored_value(name):
    """Ours within 1e-9 of the stored value; NGsolveCMStest's stored value is 1.24e-9 from the converged
    answer (Exudyn's own run with tightened tolerances is as far), so there ours meets that run to 1e-11."""
    entry = evaluated(name)
    d = entry["differences"]
    assert entry["passed"], entry["reason"]
    if name == "NGsolveCMStest":
        assert 1e-9 < d["exudyn_tight_vs_stored"] < 1.3e-9 and d["exudyn_vs_stored"] < 1e-12
        assert abs(d["ours_vs_stored"] - d["exudyn_tight_vs_stored"]) < 1e-11
        assert d["ours_vs_exudyn_tight"] <= CONVERGED_TOLERANCE
    else:
        assert d["ours_vs_stored"] <= STORED_TOLERANCE


@pytest.mark.parametrize("name", _params())
def test_ours_meets_exudyns_runs(name):
    """Exudyn's rebuild reproduces the stored value (its run at the script's settings), and ours agrees
    with it and with its converged run within 100 times the measured differences."""
    d = evaluated(name)["differences"]
    at_default, converged = MEASURED[name]
    assert d["exudyn_vs_stored"] < 1e-11
    assert d["ours_vs_exudyn"] <= 100 * at_default
    assert d["ours_vs_exudyn_tight"] <= min(100 * converged, CONVERGED_TOLERANCE)
    assert d["trajectory"]["ours_vs_exudyn_tight"] < 1e-9  # measured up to 6.6e-12 (the accelerations)


@pytest.mark.parametrize("name", ["objectFFRFreducedOrderTest", "objectFFRFreducedOrderAccelerations"])
def test_the_scripts_own_line_is_stale(name):
    """The number in the script's ``testError`` line is not what Exudyn's test suite checks: Exudyn
    1.13.6 itself misses it by 1.3e-4 and 5.7e-5, and meets the suite's reference to 2e-13."""
    d = evaluated(name)["differences"]
    assert d["in_script_vs_stored"] > 1e-5
    assert relative(evaluated(name)["exudyn"]["result"], model_named(name).stored.in_script) > 1e-5


def test_the_reduced_form_of_objectffrftest2_has_every_elastic_motion():
    """339 = 3 x 115 - 6 orthonormal columns, each satisfying ObjectFFRF's six Tisserand rows, and with the
    six rigid motions they span every displacement."""
    model = FFRF_TEST2.fe_model()
    basis = tisserand_basis(model)
    assert basis.shape == (345, 339)
    np.testing.assert_allclose(basis.T @ basis, np.eye(339), atol=1e-12)
    translations = np.kron(np.ones((115, 1)), np.eye(3))
    assert np.abs(translations.T @ (model.mass @ basis)).max() < 1e-12
    rotations = np.cross(np.eye(3)[:, None, :], model.nodes[None, :, :]).reshape(3, -1).T  # e_a x x_i
    assert np.abs(rotations.T @ (model.mass @ basis)).max() < 1e-12
    assert np.linalg.matrix_rank(np.hstack([basis, translations, rotations])) == 345


def test_the_netgen_pickle_is_read_as_exudyn_reads_it():
    """Our allow-listed reading of netgenTestMesh.pkl gives Exudyn's LoadFromFile nodes, M, K and surface."""
    from exudyn.FEM import FEMinterface

    model, triangles = netgen_model()
    fem = FEMinterface()
    fem.LoadFromFile(str(DATA / "netgenTestMesh"), mode="PKL")  # blob id checked by netgen_model above
    np.testing.assert_array_equal(model.nodes, fem.GetNodePositionsAsArray())
    assert abs(model.mass - fem.GetMassMatrix()).max() == 0.0
    assert abs(model.stiffness - fem.GetStiffnessMatrix()).max() == 0.0
    np.testing.assert_array_equal(triangles, np.asarray(fem.surface[0]["Trigs"]))


def test_the_pickle_reader_refuses_other_files_and_other_code(tmp_path):
    """A file with another blob id is not unpickled; a pickle naming anything but NumPy arrays and the two
    stand-ins is refused before it runs."""
    other = tmp_path / "other.pkl"
    other.write_bytes(pickle.dumps({"type": "FEMinterface"}))
    with pytest.raises(ValueError, match="blob id"):
        read_fem_pickle(other, NETGEN_PICKLE_BLOB)

    class Payload:
        def __reduce__(self):
            return (print, ("unpickled",))

    raw = pickle.dumps(Payload())
    from validation.testmodels.fe_data import git_blob_id

    other.write_bytes(raw)
    with pytest.raises(pickle.UnpicklingError, match="allow-list"):
        read_fem_pickle(other, git_blob_id(raw))


def test_judge_explains_only_exudyns_own_newton_error():
    """The converged-run rule needs Exudyn's run at the script's settings to reproduce the stored value: a
    wrong stored value fails even when ours meets Exudyn's converged run."""
    stored, converged = 1.0, 1.0 + 1.24e-9
    assert judge(stored, converged + 1e-13, stored + 1e-14, converged).passed
    assert not judge(stored, converged + 1e-13).passed  # without Exudyn: 1e-9 against the stored value
    assert not judge(stored * (1 + 1e-6), converged, stored, converged).passed
    assert not judge(stored, converged + 1e-10, stored, converged).passed


def test_the_command_exits_0_when_all_agree_and_writes_json(tmp_path, capsys):
    out = tmp_path / "testmodels.json"
    assert main(["testmodels", "--models", "superElementRigidJointTest", "NGsolveCMStest", "--json", str(out)]) == 0
    results = json.loads(out.read_text())
    assert results["passed"] and set(results["models"]) == {"superElementRigidJointTest", "NGsolveCMStest"}
    entry = results["models"]["superElementRigidJointTest"]
    assert entry["stored"]["value"] == 0.015217208913989071 and entry["exudyn"]["result"] > 0
    printed = capsys.readouterr().out
    assert "superElementRigidJointTest: PASS" in printed and "2 of 2 models passed" in printed


def test_the_command_exits_1_when_a_stored_value_is_perturbed(monkeypatch, capsys):
    """The stored value 1e-7 off (relative): ours misses it, and Exudyn's runs do not explain it."""
    perturbed = tuple(
        dataclasses.replace(m, stored=dataclasses.replace(m.stored, value=m.stored.value * (1 + 1e-7)))
        if m.name == "superElementRigidJointTest"
        else m
        for m in TESTMODELS
    )
    monkeypatch.setattr(testmodels_report, "TESTMODELS", perturbed)
    assert main(["testmodels", "--models", "superElementRigidJointTest"]) == 1
    assert "superElementRigidJointTest: FAIL" in capsys.readouterr().out


def test_the_command_exits_2_when_a_run_fails(monkeypatch, capsys):
    def broken(tolerance):
        raise RuntimeError("no model")

    failing = tuple(dataclasses.replace(m, ours=broken) if m.name == "NGsolveCMStest" else m for m in TESTMODELS)
    monkeypatch.setattr(testmodels_report, "TESTMODELS", failing)
    assert main(["testmodels", "--models", "NGsolveCMStest", "--no-exudyn"]) == 2
    assert "no model" in capsys.readouterr().err
