"""Every fix that changed a result has a known problem: each top-level entry of a
CHANGELOG.md ``### Fixed`` section (every version) that speaks of a verdict, an exit code or
generated code names a ``KP-NNN`` of src/fretc/qualification/known_problems.toml, or says
why no result changed (``No result changed: <reason>``); every KP id the CHANGELOG names
exists."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fretc.qualification.catalogue import KP_ID, load_known_problems

REPO = Path(__file__).resolve().parents[2]
CHANGELOG = REPO / "CHANGELOG.md"

#: an entry that speaks of a result: a verdict word, a clean exit, generated code
RESULT = re.compile(r"\b(satisfied|violated|vacuous|unknown|exit 0|holds|passed|verdicts?|"
                    r"generated)\b|--emit\b", re.I)
#: the explicit statement that a fix changed no result, with its reason
NO_RESULT = re.compile(r"No result changed: *\S")


def fixed_entries(text: str) -> list[tuple[int, str]]:
    """The top-level items (``- `` at the line's start, with their indented continuation
    lines) of every ``### Fixed`` section of a CHANGELOG text, each with its first line's
    number."""
    entries: list[tuple[int, str]] = []
    in_fixed = False
    current: list | None = None
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("#"):
            in_fixed = line.strip() == "### Fixed"
            current = None
            continue
        if not in_fixed:
            continue
        if line.startswith("- "):
            current = [number, line[2:]]
            entries.append(current)  # type: ignore[arg-type]
        elif current is not None and (line.startswith(" ") or not line.strip()):
            current[1] += " " + line.strip()
        else:
            current = None
    return [(n, " ".join(t.split())) for n, t in entries]


def uncited(text: str, known: set[str]) -> list[str]:
    """The Fixed entries of a CHANGELOG text that changed a result (:data:`RESULT`) and
    name no known KP id nor say ``No result changed:``, as ``line N: start``."""
    out = []
    for number, entry in fixed_entries(text):
        if not RESULT.search(entry):
            continue
        if set(KP_ID.findall(entry)) & known or NO_RESULT.search(entry):
            continue
        out.append(f"line {number}: {entry[:100]}")
    return out


SAMPLE = """# Changelog
## [Unreleased]
### Fixed
- A violation was judged satisfied (KP-001).
- A message's wording: it said unknown span. No result changed: a diagnostic's words.
- A generated
  node published late.
- Faster parsing.
### Added
- A new verdict word.
## [0.1.0]
### Fixed
- The C runner's exit 0 on a violation.
"""


def test_the_parser_reads_every_fixed_section_and_its_continuation_lines():
    entries = fixed_entries(SAMPLE)
    assert [n for n, _ in entries] == [4, 5, 6, 8, 13]
    assert entries[2][1] == "A generated node published late."
    assert uncited(SAMPLE, {"KP-001"}) == ["line 6: A generated node published late.",
                                           "line 13: The C runner's exit 0 on a violation."]
    # a citation of an id the catalogue does not hold is no citation
    assert len(uncited(SAMPLE, set())) == 3


@pytest.mark.tor("TOR-QUA-001")
def test_every_fixed_entry_that_changed_a_result_names_its_known_problem():
    known = {p.id for p in load_known_problems()}
    missing = uncited(CHANGELOG.read_text(encoding="utf-8"), known)
    assert not missing, ("Fixed entries that changed a verdict, a clean pass or generated "
                         "code without a KP-NNN of known_problems.toml nor 'No result "
                         "changed: <why>':\n" + "\n".join(missing))


@pytest.mark.tor("TOR-QUA-001")
def test_every_known_problem_the_changelog_names_exists():
    known = {p.id for p in load_known_problems()}
    named = set(KP_ID.findall(CHANGELOG.read_text(encoding="utf-8")))
    assert named and not named - known, sorted(named - known)
