"""fretc's tool operational requirements and known problems, each kept in one TOML file of
this package (``requirements.toml``, ``known_problems.toml``), read and checked here, and the
documentation pages made from them (docs/qualification/requirements.md and
known-problems.md are these renderings: ``python -m fretc.qualification.catalogue DOCS``
writes them, and a test fails when a page differs).

Design notes: ARCHITECTURE.md, `qualification/catalogue.py`."""

from __future__ import annotations

import re
import sys
import tomllib
from dataclasses import dataclass
from functools import cache
from pathlib import Path

HERE = Path(__file__).parent
#: the severities of a known problem (what the problem does to a user's result)
SEVERITIES = ("wrong verdict", "refuses valid input", "accepts invalid input", "diagnostic",
              "performance", "side effect")
#: the uses of a requirement (IEC 61508-3 7.4.4.2's tool classes)
USES = ("T2", "T3")
TOR_ID = re.compile(r"TOR-[A-Z]{3}-\d{3}")
KP_ID = re.compile(r"KP-\d{3}")


class CatalogueError(ValueError):
    """A requirements or known-problems file that breaks its schema (module docstring);
    the message names the entry and the field."""


@dataclass(frozen=True)
class Requirement:
    """A tool operational requirement (module docstring)."""

    id: str
    area: str
    statement: str
    source: str
    use: str
    not_verified: str | None = None


@dataclass(frozen=True)
class KnownProblem:
    """A known problem (module docstring)."""

    id: str
    title: str
    severity: str
    affected: str
    detection: str
    workaround: str
    test: str
    fixed_in: str


def _entries(text: str, table: str, fields: dict[str, bool], where: str) -> list[dict]:
    """The ``[[table]]`` entries of a TOML text, each checked to hold exactly ``fields``
    (name -> required) as non-empty strings. Raises :class:`CatalogueError`."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CatalogueError(f"{where}: {exc}") from None
    if set(doc) != {table} or not isinstance(doc[table], list):
        raise CatalogueError(f"{where}: one array of tables [[{table}]] expected")
    out = []
    for i, entry in enumerate(doc[table]):
        name = f"{where}: [[{table}]] {i + 1} ({entry.get('id', 'no id')})"
        extra = set(entry) - set(fields)
        missing = {f for f, required in fields.items() if required} - set(entry)
        if extra or missing:
            raise CatalogueError(f"{name}: unknown fields {sorted(extra)}, missing "
                                 f"{sorted(missing)}")
        for key, value in entry.items():
            if not isinstance(value, str) or not value.strip():
                raise CatalogueError(f"{name}: {key} must be a non-empty string")
        out.append(entry)
    return out


def parse_requirements(text: str, where: str = "requirements.toml") -> list[Requirement]:
    """The requirements of a ``requirements.toml`` text, checked: ids of the form
    ``TOR-XXX-000``, unique; ``use`` in :data:`USES`. Raises :class:`CatalogueError`."""
    fields = {"id": True, "area": True, "statement": True, "source": True, "use": True,
              "not_verified": False}
    reqs = [Requirement(**e) for e in _entries(text, "requirement", fields, where)]
    seen: set[str] = set()
    for r in reqs:
        if not TOR_ID.fullmatch(r.id) or r.id in seen:
            raise CatalogueError(f"{where}: {r.id}: not of the form TOR-XXX-000, or twice")
        if r.use not in USES:
            raise CatalogueError(f"{where}: {r.id}: use {r.use!r} is not one of {USES}")
        seen.add(r.id)
    return reqs


def parse_known_problems(text: str, where: str = "known_problems.toml") -> list[KnownProblem]:
    """The known problems of a ``known_problems.toml`` text, checked: ids ``KP-000``,
    unique; ``severity`` in :data:`SEVERITIES`; ``test`` a pytest node id under ``tests/``
    (``tests/...py::name``). Raises :class:`CatalogueError`."""
    fields = {f: True for f in KnownProblem.__dataclass_fields__}
    probs = [KnownProblem(**e) for e in _entries(text, "problem", fields, where)]
    seen: set[str] = set()
    for p in probs:
        if not KP_ID.fullmatch(p.id) or p.id in seen:
            raise CatalogueError(f"{where}: {p.id}: not of the form KP-000, or twice")
        if p.severity not in SEVERITIES:
            raise CatalogueError(f"{where}: {p.id}: severity {p.severity!r} is not one of "
                                 f"{SEVERITIES}")
        if not re.fullmatch(r"tests/[\w/]+\.py::\w+(\[[^\]]+\])?", p.test):
            raise CatalogueError(f"{where}: {p.id}: test {p.test!r} is not a node id "
                                 "tests/....py::test_name")
        seen.add(p.id)
    return probs


@cache
def load_requirements() -> tuple[Requirement, ...]:
    """The installed ``requirements.toml``'s requirements (:func:`parse_requirements`)."""
    return tuple(parse_requirements((HERE / "requirements.toml").read_text("utf-8")))


@cache
def load_known_problems() -> tuple[KnownProblem, ...]:
    """The installed ``known_problems.toml``'s entries (:func:`parse_known_problems`)."""
    return tuple(parse_known_problems((HERE / "known_problems.toml").read_text("utf-8")))


def _cell(text: str) -> str:
    """Text in a Markdown table cell: ``|`` escaped, lines joined."""
    return " ".join(text.split()).replace("|", "\\|")


def requirements_page(reqs: tuple[Requirement, ...] | list[Requirement]) -> str:
    """docs/qualification/requirements.md: one table per area, in the file's order."""
    lines = ["# Tool operational requirements", "",
             "<!-- generated from src/fretc/qualification/requirements.toml by "
             "`python -m fretc.qualification.catalogue docs/qualification`: edit that file -->",
             "", "What fretc guarantees, one statement each, with where its rule comes from "
             "and its use (T2: an analysis whose fault can hide a defect; T3: code that runs "
             "on the robot). Ids are stable across versions. The tests that show each one "
             "are traced by the `tor` pytest marker ([the kit](index.md#traced-tests)); a "
             "requirement no test shows says why.", ""]
    areas: dict[str, list[Requirement]] = {}
    for r in reqs:
        areas.setdefault(r.area, []).append(r)
    for area, items in areas.items():
        lines += [f"## {area}", "", "| id | statement | source | use |", "|---|---|---|---|"]
        for r in items:
            note = f" **Not verified:** {_cell(r.not_verified)}" if r.not_verified else ""
            lines.append(f"| {r.id} | {_cell(r.statement)}{note} | {_cell(r.source)} | "
                         f"{r.use} |")
        lines.append("")
    return "\n".join(lines)


def known_problems_page(probs: tuple[KnownProblem, ...] | list[KnownProblem]) -> str:
    """docs/qualification/known-problems.md: the open problems, then the fixed ones."""
    lines = ["# Known problems", "",
             "<!-- generated from src/fretc/qualification/known_problems.toml by "
             "`python -m fretc.qualification.catalogue docs/qualification`: edit that file -->",
             "", "Each problem with its severity, the versions it affects, how to find it in "
             "your own outputs, what to do about it, the test that reproduces it and where "
             "it was fixed. Severities: " + ", ".join(SEVERITIES) + ".", ""]
    for title, items in (("Open", [p for p in probs if p.fixed_in == "open"]),
                         ("Fixed", [p for p in probs if p.fixed_in != "open"])):
        lines += [f"## {title}", ""]
        for p in items:
            lines += [f"### {p.id}: {p.title}", "",
                      f"- **Severity:** {p.severity}", f"- **Affected:** {p.affected}",
                      f"- **How to detect it:** {' '.join(p.detection.split())}",
                      f"- **Workaround:** {' '.join(p.workaround.split())}",
                      f"- **Reproduced by:** `{p.test}`", f"- **Fixed in:** {p.fixed_in}", ""]
    return "\n".join(lines)


def write_pages(folder: Path) -> list[Path]:
    """Write requirements.md and known-problems.md into ``folder``; returns their paths."""
    out = []
    for name, text in (("requirements.md", requirements_page(load_requirements())),
                       ("known-problems.md", known_problems_page(load_known_problems()))):
        (folder / name).write_text(text, encoding="utf-8")
        out.append(folder / name)
    return out


if __name__ == "__main__":
    for written in write_pages(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/qualification")):
        print(written)
