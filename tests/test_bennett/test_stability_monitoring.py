"""Stability along a quasi-static run (``--stability``, Eq. (B1)): the paper's nominal PLA Bennett linkage has no
unstable pose over a revolution, and its smallest squared frequency is the lowest vibration of the linkage."""

from __future__ import annotations

import json

import numpy as np

from ffrf.cli import main


def test_the_nominal_pla_bennett_is_stable_over_a_revolution(tmp_path, capsys):
    """Coarse links (12 mm, P1, 2 modes), 25 quasi-static poses: every equilibrium's smallest squared frequency is
    positive (a linkage that moves smoothly, as the paper's prints do), the run says where the margin is smallest,
    and stability.json and stability.png are written."""
    code = main(
        ["bennett", "--variant", "pla", "--h", "0.012", "--order", "1", "--modes", "2", "--outputs", "25",
         "--quasi-static", "--stability", "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 0
    table = json.loads((tmp_path / "stability.json").read_text())
    values = np.array(table["squared_frequencies_rad2_per_s2"])
    assert values.shape == (25, 3) and np.all(values[:, 0] > 0.0)
    summary = table["summary"]
    assert summary["unstable_poses"] == 0 and summary["min_squared_frequency"] == values[:, 0].min()
    assert (tmp_path / "stability.png").is_file()
    assert "stability: smallest squared frequency" in capsys.readouterr().out


def test_stability_of_a_dynamic_run_is_refused(tmp_path, capsys):
    code = main(["bennett", "--h", "0.012", "--order", "1", "--modes", "2", "--dynamic", "--stability",
                 "--out", str(tmp_path)])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "stability is judged at equilibria" in err
