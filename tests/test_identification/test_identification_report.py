"""Tables in the paper's layout and figures."""

import numpy as np
from identification_fixtures import ideal_record

from identification import identify_dh, run_statistics
from identification.report import dh_table_csv, dh_table_markdown, plot_axis3_deviation, plot_axis_fits
from kinematics import BennettLinkage


def test_tables_and_figures(tmp_path, rng):
    linkage = BennettLinkage.paper()
    points = ideal_record(linkage, np.linspace(0, 2 * np.pi, 200, endpoint=False), 1, rng)
    loop = identify_dh(points)
    stats = run_statistics([loop, loop])
    table = dh_table_markdown(stats, "ideal")
    assert "| 0 | 110.000 | 0.000 | 150.000 | 0.000 |" in table
    assert "a0/a1 = 0.50000" in table and "sin α0/sin α1 = 0.50000" in table
    rows = dh_table_csv(stats, "ideal").splitlines()
    assert rows[0].startswith("label,i,a_mm") and rows[2].startswith("ideal,1,220.000000")
    fig, _ = plot_axis_fits(points, loop.fits)
    fig.savefig(tmp_path / "fits.png")
    fig, ax = plot_axis3_deviation(["PLA", "PLA 1 deg"], [stats, stats])
    fig.savefig(tmp_path / "axis3.png")
    assert (tmp_path / "fits.png").stat().st_size > 5000 and len(ax.get_xticklabels()) == 2
