"""The kit's two data files (src/fretc/qualification/requirements.toml and
known_problems.toml): their schema, the pages rendered from them, and the tests the known
problems name."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fretc.qualification import catalogue
from fretc.qualification.catalogue import (CatalogueError, load_known_problems,
                                           load_requirements, parse_known_problems,
                                           parse_requirements)

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs" / "qualification"

GOOD_REQ = """[[requirement]]
id = "TOR-ABC-001"
area = "An area"
statement = "It holds."
source = "a paper"
use = "T2"
"""
GOOD_KP = """[[problem]]
id = "KP-001"
title = "A problem"
severity = "diagnostic"
affected = "0.1.0"
detection = "look"
workaround = "none"
test = "tests/a/test_b.py::test_c"
fixed_in = "open"
"""


@pytest.mark.tor("TOR-QUA-001")
def test_the_shipped_files_follow_their_schema():
    reqs, probs = load_requirements(), load_known_problems()
    assert len({r.id for r in reqs}) == len(reqs) >= 50
    assert {p.severity for p in probs} <= set(catalogue.SEVERITIES)
    # the areas the kit must cover, each with requirements
    areas = {r.area for r in reqs}
    for area in ("FRETish grammar", "FRET semantics", "Tick rules", "Signal bindings",
                 "Verdicts", "Damage and gaps", "Generated monitors", "Shield",
                 "fretc check", "fretc watch"):
        assert area in areas
    # the wrong-result findings of the project's history; each fixed one says where
    assert sum(p.severity == "wrong verdict" for p in probs) >= 10
    for p in probs:
        assert p.fixed_in == "open" or re.search(r"\bcommits? [0-9a-f]{7}|\b\d+\.\d+\.\d+\b",
                                                 p.fixed_in), p.id
    # the file keeps its open problems first (its comment says so; the page shows both)
    fixed = [p.fixed_in != "open" for p in probs]
    assert fixed == sorted(fixed)


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('"TOR-ABC-001"', '"TOR-1"'), "not of the form"),
    (lambda t: t + t, "twice"),
    (lambda t: t.replace('use = "T2"', 'use = "T9"'), "use 'T9'"),
    (lambda t: t + 'colour = "red"\n', "unknown fields ['colour']"),
    (lambda t: t.replace('source = "a paper"\n', ""), "missing ['source']"),
    (lambda t: t.replace('"It holds."', '""'), "non-empty string"),
    (lambda t: t.replace("[[requirement]]", "[requirement]"), "one array of tables"),
])
def test_a_requirements_file_that_breaks_the_schema_is_refused_naming_the_entry(edit, words):
    assert [r.id for r in parse_requirements(GOOD_REQ)] == ["TOR-ABC-001"]
    with pytest.raises(CatalogueError, match=re.escape(words)):
        parse_requirements(edit(GOOD_REQ))


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('"diagnostic"', '"annoying"'), "severity 'annoying'"),
    (lambda t: t.replace("tests/a/test_b.py::test_c", "test_c"), "not a node id"),
    (lambda t: t.replace('"KP-001"', '"KP-1"'), "not of the form"),
    (lambda t: t.replace('fixed_in = "open"\n', ""), "missing ['fixed_in']"),
])
def test_a_known_problems_file_that_breaks_the_schema_is_refused(edit, words):
    assert [p.id for p in parse_known_problems(GOOD_KP)] == ["KP-001"]
    with pytest.raises(CatalogueError, match=re.escape(words)):
        parse_known_problems(edit(GOOD_KP))


@pytest.mark.tor("TOR-QUA-001")
def test_each_known_problem_names_a_test_that_exists():
    for p in load_known_problems():
        path, name = p.test.split("::")
        source = (REPO / path).read_text(encoding="utf-8")
        assert re.search(rf"^(async )?def {name.split('[')[0]}\(", source, re.M), p.id


def test_the_docs_pages_are_the_files_rendered():
    # docs/qualification/requirements.md and known-problems.md are generated (one source):
    # python -m fretc.qualification.catalogue docs/qualification writes them again
    assert (DOCS / "requirements.md").read_text(encoding="utf-8") == \
        catalogue.requirements_page(load_requirements())
    assert (DOCS / "known-problems.md").read_text(encoding="utf-8") == \
        catalogue.known_problems_page(load_known_problems())


def test_the_pages_show_every_entry_and_escape_table_cells():
    reqs = parse_requirements(GOOD_REQ.replace("It holds.", "a | b holds."))
    page = catalogue.requirements_page(reqs)
    assert "| TOR-ABC-001 | a \\| b holds. | a paper | T2 |" in page
    page = catalogue.known_problems_page(parse_known_problems(GOOD_KP))
    assert "### KP-001: A problem" in page and "## Open" in page
