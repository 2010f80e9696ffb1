"""Every tool operational requirement is shown by a test (its ``tor`` marker) or says why
not, and every marker names a requirement that exists: the default suite fails otherwise
(tests/tor_matrix.py reads the markers from the test sources; CI makes the matrix with the
last results)."""

from __future__ import annotations

from pathlib import Path

import pytest
from tor_matrix import junit_results, markers, matrix, problems

from fretc.qualification.catalogue import Requirement, load_requirements


@pytest.mark.tor("TOR-QUA-001")
def test_every_requirement_is_traced_and_every_marker_is_known():
    reqs, marked = list(load_requirements()), markers()
    assert problems(reqs, marked) == []
    # a test names only requirements of the file, and most requirements have tests
    shown = {i for ids in marked.values() for i in ids}
    assert len(shown) >= len(reqs) - sum(bool(r.not_verified) for r in reqs)


def test_an_unknown_marker_or_an_untraced_requirement_is_found(tmp_path: Path):
    reqs = [Requirement("TOR-AAA-001", "a", "s", "src", "T2"),
            Requirement("TOR-AAA-002", "a", "s", "src", "T2", not_verified="why"),
            Requirement("TOR-AAA-003", "a", "s", "src", "T2")]
    folder = tmp_path / "tests" / "x"
    folder.mkdir(parents=True)
    (folder / "test_y.py").write_text(
        "import pytest\n"
        "pytestmark = [pytest.mark.tor('TOR-AAA-003')]\n"
        "@pytest.mark.tor('TOR-AAA-001', 'TOR-ZZZ-009')\n"
        "def test_a():\n    pass\n"
        "class TestB:\n"
        "    @pytest.mark.tor('TOR-AAA-002')\n"
        "    def test_c(self):\n        pass\n"
        "def test_unmarked():\n    pass\n", encoding="utf-8")
    import tor_matrix

    old = tor_matrix.REPO
    tor_matrix.REPO = tmp_path
    try:
        marked = markers(tmp_path / "tests")
    finally:
        tor_matrix.REPO = old
    assert marked == {
        "tests/x/test_y.py::test_a": ["TOR-AAA-001", "TOR-AAA-003", "TOR-ZZZ-009"],
        "tests/x/test_y.py::TestB::test_c": ["TOR-AAA-002", "TOR-AAA-003"],
        "tests/x/test_y.py::test_unmarked": ["TOR-AAA-003"]}
    assert problems(reqs, marked) == [
        "tests/x/test_y.py::test_a: unknown requirement TOR-ZZZ-009",
        "TOR-AAA-002: tests show it, but it is marked not verified"]
    assert problems(reqs[:1], {}) == [
        "TOR-AAA-001: no test shows it and no not_verified reason says why"]


def test_the_matrix_carries_each_tests_last_result(tmp_path: Path):
    xml = tmp_path / "junit.xml"
    xml.write_text(
        '<testsuites><testsuite name="pytest">'
        '<testcase classname="tests.x.test_y" name="test_a[1]"/>'
        '<testcase classname="tests.x.test_y" name="test_a[2]"><failure message="no"/>'
        '</testcase>'
        '<testcase classname="tests.x.test_y.TestB" name="test_c"><skipped/></testcase>'
        '<testcase classname="tests.x.test_y" name="test_d"/>'
        '</testsuite></testsuites>', encoding="utf-8")
    results = junit_results(xml)
    assert results == {"tests/x/test_y.py::test_a": "failed",
                       "tests/x/test_y.py::TestB::test_c": "skipped",
                       "tests/x/test_y.py::test_d": "passed"}
    reqs = [Requirement("TOR-AAA-001", "a", "s", "src", "T2"),
            Requirement("TOR-AAA-002", "a", "s", "src", "T2", not_verified="no rig")]
    text = matrix(reqs, {"tests/x/test_y.py::test_a": ["TOR-AAA-001"],
                         "tests/x/test_y.py::test_e": ["TOR-AAA-001"]}, results)
    assert "| TOR-AAA-001 | `tests/x/test_y.py::test_a` | failed |" in text
    assert "| TOR-AAA-001 | `tests/x/test_y.py::test_e` | not run |" in text
    assert "| TOR-AAA-002 | not verified: no rig | |" in text


@pytest.mark.tor("TOR-QUA-001")
def test_the_gate_fails_on_a_failed_a_not_run_or_an_all_skipped_traced_test():
    """With results, the matrix fails a requirement whose traced test failed or was not run,
    or whose traced tests were all skipped; one passed beside a skipped one is shown."""
    reqs = [Requirement(f"TOR-AAA-00{k}", "a", "s", "src", "T2") for k in range(1, 5)]
    marked = {"t.py::a": ["TOR-AAA-001"], "t.py::b": ["TOR-AAA-002"],
              "t.py::c": ["TOR-AAA-003"], "t.py::d": ["TOR-AAA-003", "TOR-AAA-004"],
              "t.py::e": ["TOR-AAA-004"]}
    results = {"t.py::a": "failed", "t.py::c": "skipped", "t.py::d": "skipped",
               "t.py::e": "passed"}
    assert problems(reqs, marked) == []
    assert problems(reqs, marked, results) == [
        "TOR-AAA-001: its traced test t.py::a failed",
        "TOR-AAA-002: its traced test t.py::b not run",
        "TOR-AAA-003: every traced test was skipped (2)"]
    assert problems(reqs, marked, {n: "passed" for n in marked}) == []
