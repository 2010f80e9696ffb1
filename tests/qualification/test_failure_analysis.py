"""The failure analysis (docs/qualification/failure-analysis.md): each row names how its
failure is detected, and every name is real: a check of ``fretc qualify`` (its suite's
names) or a test function of the project; a check marked *seeded* is one a fault of the
mutation run is meant for."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from fretc.qualification.faults import FAULTS
from fretc.qualification.suite import CHECKS

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "qualification" / "failure-analysis.md"


def _rows() -> list[list[str]]:
    """The table's rows (cells, the header and its rule left out)."""
    lines = [ln for ln in PAGE.read_text(encoding="utf-8").splitlines() if ln.startswith("|")]
    return [[c.strip() for c in ln.strip("|").split("|")] for ln in lines[2:]]


def _test_exists(node: str) -> bool:
    """``tests/x/test_y.py::test_z`` names a test function of that file."""
    path, _, name = node.partition("::")
    file = REPO / path
    if not file.is_file():
        return False
    tree = ast.parse(file.read_text(encoding="utf-8"))
    return any(isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name == name
               for n in ast.walk(tree))


@pytest.mark.tor("TOR-QUA-001")
def test_every_row_names_checks_and_tests_that_exist():
    rows = _rows()
    assert len(rows) >= 20 and all(len(r) == 5 for r in rows)
    checks = {c.name for c in CHECKS}
    seeded = {name for f in FAULTS.values() for name in f.first}
    named = set()
    for component, _failure, risk, _mitigation, detection in rows:
        names = re.findall(r"`([^`]+)`", detection)
        assert names, component
        assert re.match(r"(wrong verdict|side effect|diagnostic)", risk), component
        for name in names:
            if "::" in name:
                assert _test_exists(name), (component, name)
            else:
                assert name in checks, (component, name)
                named.add(name)
        for name in re.findall(r"`([^`]+)` \(seeded\)", detection):
            assert name in seeded, (component, name)
    # every check of the suite and every seeded fault's check appear in some row
    assert checks - named == set() and seeded <= named
