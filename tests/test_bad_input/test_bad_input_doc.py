"""docs/bad_input.md cannot drift: every row names a test that exists, every scene-file case of
``test_scene_input.CASES`` has its row, and the stated count is the number of rows."""

import re
from pathlib import Path

from test_scene_input import CASES

ROOT = Path(__file__).parents[2]
DOC = (ROOT / "docs" / "bad_input.md").read_text()
ROWS = [line for line in DOC.splitlines() if line.startswith("| ") and not line.startswith(("| input", "| ---"))]
REFERENCE = re.compile(r"`(tests/[\w/]+\.py)::(test_\w+)(?:\[([^\]]+)\])?`")


def test_every_row_names_an_existing_test():
    assert len(ROWS) >= 25
    for row in ROWS:
        match = REFERENCE.search(row)
        assert match, row
        path, name, case = match.groups()
        source = (ROOT / path).read_text()
        assert re.search(rf"^def {name}\(", source, re.MULTILINE), (path, name)
        if case is not None:
            assert f'"{case}"' in source, (path, case)


def test_every_scene_case_is_documented_and_the_count_is_right():
    for case in CASES:
        assert f"::test_bad_scene_is_refused_with_a_clear_message[{case}]`" in DOC, case
    assert f"\n{len(ROWS)} classes.\n" in DOC
