"""Every measured figure of README.md and docs/*.md is a link into a result file
``docs/results/NAME.json`` and reads what that file says (``scripts/update_docs.py``); every
result file says how it was measured (``ffrf/output/provenance.py``)."""

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = sorted((ROOT / "docs" / "results").glob("*.json"))


def _update_docs():
    spec = importlib.util.spec_from_file_location("update_docs", ROOT / "scripts" / "update_docs.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("update_docs", module)
    spec.loader.exec_module(sys.modules["update_docs"])
    return sys.modules["update_docs"]


def test_every_figure_agrees_with_its_result_file():
    update_docs = _update_docs()
    problems = update_docs.check_or_update_tables() + update_docs.check_or_update()
    assert not problems, "run scripts/update_docs.py, or re-measure:\n" + "\n".join(problems)


def test_the_docs_cite_result_files():
    update_docs = _update_docs()
    cited = {(f.doc.parent / f.path).resolve() for doc in update_docs.DOCS for f in update_docs.figures(doc)}
    assert len(cited) >= 3
    assert all(path.parent == ROOT / "docs" / "results" for path in cited)


@pytest.mark.parametrize("path", RESULTS, ids=[p.stem for p in RESULTS])
def test_result_file_says_how_it_was_measured(path):
    data = json.loads(path.read_text())
    meta = data["meta"]
    assert meta["command"] and meta["date"].endswith("+00:00")
    assert meta["machine"]["cpu"] and meta["machine"]["cores"] >= 1
    assert "load_average_start" in meta["machine"] and "load_average_end" in meta["machine"]
    assert {"python", "numpy", "scipy"} <= set(meta["versions"])
    assert "git" in meta
    assert "results" in data


def test_figure_formats():
    update_docs = _update_docs()
    assert update_docs.format_like("0.134", 1.3427e-4 / 1e-3) == "0.134"
    assert update_docs.format_like("4.5e-10", 4.475e-10) == "4.5e-10"
    assert update_docs.format_like("36", 35.6) == "36"
    assert update_docs.stored_unit("/results/variants/pla/max_abs_driving_torque_Nmm") == "N mm"
    assert update_docs.stored_unit("/results/variants/pla/wall_time_s/build") == "s"
    assert update_docs.stored_unit("/results/pla/torque/max_rel_diff") is None


def test_a_wrong_figure_is_listed_and_rewritten(tmp_path):
    update_docs = _update_docs()
    result = ROOT / "docs" / "results" / "validation_summary.json"
    pointer = "/results/pla/metrics/coupler_deviation_from_ideal_m/inhouse"
    value = json.loads(result.read_text())["results"]["pla"]["metrics"]["coupler_deviation_from_ideal_m"]["inhouse"]
    doc = tmp_path / "doc.md"
    doc.write_text(f"deviation [9.99 mm]({result}#{pointer}), missing [1 m]({result}#/results/nowhere)\n")
    problems = update_docs.check_or_update([doc])
    assert len(problems) == 2 and "should read" in problems[0] and "no key 'nowhere'" in problems[1]
    update_docs.check_or_update([doc], update=True)
    assert f"[{1e3 * value:.2f} mm]" in doc.read_text()
