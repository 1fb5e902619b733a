"""Bad study files and study commands are refused with one line naming the key and the fix (exit status 2),
before any worker starts."""

import pytest

from ffrf.cli import main

GOOD = """
[study]
method = "sobol"
samples = 8

[base]
bennett = "pla"

[[parameters]]
name = "twist"
target = "bore_twist_deg"
joint = 3
link = 0
normal = {mean = 0.0, std = 0.5}
"""

#: A grid of two parameters of 1000 values each.
GRID_1000_BY_1000 = 'method = "grid"\n\n[base]\nbennett = "pla"\n' + "".join(
    f'\n[[parameters]]\nname = "{name}"\ntarget = "{name}"\nvalues = {list(range(1, 1001))}\n' for name in ("E", "rho")
)

CASES = {
    "unknown method": (('method = "sobol"', 'method = "random"'), "'method' must be one of"),
    "samples not a power of 2": (("samples = 8", "samples = 10"), "use 8 or 16"),
    "grid without values": (('method = "sobol"', 'method = "grid"'), "a grid study takes values = [...]"),
    "bore without its link": (("link = 0\n", ""), "give joint = J and link = L"),
    "bore on a link without that joint": (("link = 0", "link = 2"), "link 2 does not carry joint 3"),
    "two distributions": (("normal = {", "uniform = {low = 0.0, high = 1.0}\nnormal = {"), "exactly one of uniform"),
    "no base": (('bennett = "pla"', ""), "give exactly one base"),
    "stability of a dynamic study": (
        ('bennett = "pla"', 'bennett = "pla"\nmode = "dynamic"\nstability = true'),
        "stability is judged at equilibria",
    ),
    "parameter named like an output": (('name = "twist"', 'name = "max_coupler_deviation_m"'), "taken by a result"),
    # issue #32: sizes refused with their estimate and the key that lifts the limit
    "grid of a million variants": (
        (GOOD[GOOD.index('method = "sobol"') :], GRID_1000_BY_1000),  # 1e6 rows of 2 values of 8 bytes: 15.3 MiB
        "the design has 1e+06 variants (more than 1e+05; its unit samples alone take 15.3 MiB",
    ),
    "Latin hypercube of 1e12 samples": (
        ('method = "sobol"\nsamples = 8', 'method = "lhs"\nsamples = 1000000000000'),
        "1e+12 variants (more than 1e+05; its unit samples alone take 7.28 TiB",
    ),
    "Saltelli design above the limit": (
        ('method = "sobol"\nsamples = 8', 'method = "saltelli"\nsamples = 65536'),  # 65536 (1 + 2) rows
        "1.97e+05 variants",
    ),
    "base without modes": (('bennett = "pla"', 'bennett = "pla"\nmodes = 0'), "'modes' must be >= 1"),
    "base of a million revolutions": (
        ('bennett = "pla"', 'bennett = "pla"\nrevolutions = 1e6'),
        "1.2e+08 time steps per variant",
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_study_is_refused_with_a_clear_message(case, tmp_path, capsys):
    (old, new), message = CASES[case]
    assert old in GOOD
    path = tmp_path / "study.toml"
    path.write_text(GOOD.replace(old, new, 1))
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def test_zero_workers_are_refused(tmp_path, capsys):
    path = tmp_path / "study.toml"
    path.write_text(GOOD)
    with pytest.raises(SystemExit) as exit_:
        main(["study", str(path), "--out", str(tmp_path / "out"), "--workers", "0"])
    assert exit_.value.code == 2
    assert "argument --workers: must be a whole number >= 1" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "--workers sizes the local cluster"),
        (["--scheduler-file", "S.json", "--workers", "2"], "--workers sizes the local cluster"),
        (["--scheduler", "tcp://127.0.0.1:1", "--scheduler-file", "S.json"], "give the scheduler once"),
        (["--scheduler-file", "S.json"], "start the scheduler with --scheduler-file"),
    ],
)
def test_a_cluster_given_twice_or_not_there_is_refused(tmp_path, capsys, monkeypatch, options, message):
    """A scheduler given with --workers (which only a local cluster takes), a scheduler given twice, and a scheduler
    file that no scheduler wrote yet: one line naming the fix, exit 2, no output folder."""
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "study.toml"
    path.write_text(GOOD)
    assert main(["study", str(path), "--out", str(tmp_path / "out"), *options]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def test_a_report_of_a_folder_without_a_study_is_refused(tmp_path, capsys):
    assert main(["study-report", str(tmp_path)]) == 2
    assert "holds no study (no study.json)" in capsys.readouterr().err


def test_an_out_folder_of_another_study_is_refused(tmp_path, capsys):
    """A folder whose study.json is another study's (here another name and base) would mix its rows with this
    study's: refused before anything runs, naming the fix; the same study, or more samples of it, is accepted."""
    import json

    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.runner import _check_same_study, _description
    from ffrf.studies.spec import load_study

    first, second = tmp_path / "first.toml", tmp_path / "second.toml"
    first.write_text(GOOD)
    second.write_text(GOOD.replace('bennett = "pla"', 'bennett = "pla1"').replace("[study]", '[study]\nname = "other"'))
    out = tmp_path / "out"
    out.mkdir()
    (out / "study.json").write_text(json.dumps(_description(load_study(first, bases=STUDY_BASES))))
    (out / "rows").mkdir()
    assert main(["study", str(second), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds the rows of another study" in err and "another output folder (--out), or delete" in err, err
    assert len(err.strip().splitlines()) == 1
    assert json.loads((out / "study.json").read_text())["name"] == "study"  # untouched
    _check_same_study(load_study(first, bases=STUDY_BASES), out)  # its own folder
    first.write_text(GOOD.replace("samples = 8", "samples = 16"))
    _check_same_study(load_study(first, bases=STUDY_BASES), out)  # more samples of the same study


def _folder_with_a_row(tmp_path, text: str):
    """An output folder of the study ``text`` with the row of its design's first variant (its outputs NaN)."""
    import json

    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.runner import _description, _write_batch, row_schema
    from ffrf.studies.sampling import study_design
    from ffrf.studies.spec import load_study

    path = tmp_path / "study.toml"
    path.write_text(text)
    study = load_study(path, bases=STUDY_BASES)
    out = tmp_path / "out"
    out.mkdir()
    (out / "study.json").write_text(json.dumps(_description(study)))
    variant = study_design(study)[0]
    row = {"id": variant.id, "status": "ok", "block": variant.block, "sample": variant.sample} | variant.values
    _write_batch([row], row_schema(study), out)
    return path, out


def test_rows_of_another_design_are_refused_and_a_grown_design_is_not(tmp_path, capsys):
    """Another seed of a random design: the folder's row is no variant of the new design, and its rows would bias
    every estimate of it: refused in one line before anything runs (exit 2). The same study with more Sobol' samples
    keeps the row (the first points of the longer sequence): accepted, as is the study itself."""
    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.runner import _check_one_design
    from ffrf.studies.spec import load_study

    path, out = _folder_with_a_row(tmp_path, GOOD.replace("samples = 8", "samples = 8\nseed = 1"))
    _check_one_design(load_study(path, bases=STUDY_BASES), out)
    path.write_text(GOOD.replace("samples = 8", "samples = 16\nseed = 1"))
    _check_one_design(load_study(path, bases=STUDY_BASES), out)  # grown: the row stays a variant
    path.write_text(GOOD.replace("samples = 8", "samples = 8\nseed = 2"))
    assert main(["study", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds 1 row(s) of another design of this study" in err and "another output folder" in err, err
    assert len(err.strip().splitlines()) == 1


def test_rows_of_another_solver_version_are_refused(tmp_path, capsys):
    """A folder whose rows another version of the solver computed (its study.json's solver, the hash of the
    sources and libraries, differs): a resume would mix two versions' rows; refused in one line (exit 2)."""
    import json

    path, out = _folder_with_a_row(tmp_path, GOOD)
    description = json.loads((out / "study.json").read_text())
    (out / "study.json").write_text(json.dumps(description | {"solver": "0" * 64}))
    assert main(["study", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "rows computed by another version of the solver" in err and len(err.strip().splitlines()) == 1, err
