"""``python -m ffrf mesh``: files written and their content consistent with the model."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from ffrf.cli import main
from ffrf.fe.materials import PLA

ROOT = Path(__file__).resolve().parents[2]


def test_mesh_command_writes_vtu_and_summary(tmp_path):
    assert main(["mesh", "--link", "0", "--h", "0.006", "--order", "2", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "link0.json").read_text())
    mesh = meshio.read(tmp_path / "link0.vtu")
    assert summary["n_vertices"] == len(mesh.points)
    assert summary["n_tetrahedra"] == len(mesh.cells_dict["tetra"])
    assert summary["n_nodes"] > summary["n_vertices"]  # P2 midside nodes
    assert summary["mass_kg"] == pytest.approx(PLA.rho * summary["volume_m3"], rel=1e-12)
    assert set(summary["interfaces"]) == {"joint3", "joint0", "mount"}
    for interface in summary["interfaces"].values():
        assert interface["weights_sum"] == pytest.approx(1.0)
        assert interface["n_nodes"] > 10
    assert summary["interfaces"]["joint3"]["axial_offset_m"] == pytest.approx(0.0085)
    assert 0.0 < summary["quality"]["min_quality"] <= summary["quality"]["mean_quality"] <= 1.0


def test_misaligned_base_link_via_module_entry_point(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "ffrf",
            "mesh",
            "--link",
            "0",
            "--alpha3-deg",
            "91",
            "--h",
            "0.008",
            "--out",
            str(tmp_path),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "link0.json").read_text())
    h3_foot, h0_foot = np.array(summary["joint_points_m"])
    assert np.linalg.norm(h3_foot - h0_foot) == pytest.approx(0.22, rel=1e-9)
    # h3 turned by 1 deg about the common normal: (0, -sin 91, cos 91) deg, up to orientation
    alpha3 = np.radians(91.0)
    direction = np.array(summary["axes"]["joint3"]["direction"])
    assert abs(direction @ [0.0, -np.sin(alpha3), np.cos(alpha3)]) == pytest.approx(1.0, abs=1e-12)


def test_bad_arguments_give_a_clear_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:  # refused by the flag's type, as a file's h: a usage error
        main(["mesh", "--link", "1", "--h", "-1", "--out", str(tmp_path)])
    assert exit_.value.code == 2
    assert "argument --h: must be a finite number in [0.0005, 0.05] m, got '-1'" in capsys.readouterr().err


def test_paper_axes_agree_with_kinematics_dh():
    """The hard-coded home-configuration axes against the kinematics package's DH chain."""
    from ffrf.paper.axes import PAPER_AXES, bennett_axes

    for ours, theirs in zip(PAPER_AXES, bennett_axes(90.0), strict=True):
        np.testing.assert_allclose(theirs.point, ours.point, atol=1e-12)
        np.testing.assert_allclose(theirs.direction, ours.direction, atol=1e-12)


def test_warmup_compiles_the_kernels_and_says_so(capsys):
    """``python -m ffrf warmup`` (the main job's first step) runs a coarse scene through the kernels a run uses and
    reports each step; the main job after it compiles nothing more (bench/warmup.py: as fast as a warm run)."""
    from ffrf.cli import main

    assert main(["warmup"]) == 0
    err = capsys.readouterr().err
    assert "[1/1] quasi-static and stability kernels" in err
    assert "kernels ready in" in err
