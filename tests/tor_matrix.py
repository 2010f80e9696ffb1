"""The traceability matrix of the tool qualification kit: each tool operational requirement
(src/fretc/qualification/requirements.toml) -> the tests that show it (their
``@pytest.mark.tor("TOR-...")`` markers, read from the test sources without importing them)
-> each test's last result (JUnit XML files of pytest runs, ``pytest --junitxml FILE``: the default and the long
tests' runs, merged).

    python tests/tor_matrix.py [--junit FILE ...] [-o matrix.md]

prints (or writes) the matrix as Markdown and exits 1 when a requirement has neither a test
nor a ``not_verified`` reason, or a marker names an id the requirements file does not have,
and, given JUnit files, when a requirement's traced test failed or was not run in any of
them, or all its traced tests were skipped (CI runs it after the tests: .ci/run). A test's result is ``passed``, ``failed``,
``skipped`` or ``not run`` (deselected in that run: ``slow``, ``long``), over all its
parametrized cases (failed when one failed).
"""

from __future__ import annotations

import argparse
import ast
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent


def _tor_ids(node: ast.expr) -> list[str] | None:
    """The ids of a ``pytest.mark.tor("A", "B")`` expression (None when it is not one)."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
            and node.func.attr == "tor"):
        return None
    return [a.value for a in node.args if isinstance(a, ast.Constant) and isinstance(a.value, str)]


def _marks(node: ast.expr) -> list[str]:
    """The ids of every tor marker in a decorator or a ``pytestmark`` value (a marker or a
    list of them)."""
    items = node.elts if isinstance(node, (ast.List, ast.Tuple)) else [node]
    return [i for item in items for i in (_tor_ids(item) or [])]


def markers(folder: Path = TESTS) -> dict[str, list[str]]:
    """``{node id: [requirement id, ...]}`` of every test function under ``folder`` with a
    tor marker (on the function, its class or its module's ``pytestmark``); node ids as
    pytest names them (``tests/audit/test_audit.py::test_x``, ``...::Class::test_y``)."""
    out: dict[str, list[str]] = {}
    for path in sorted(folder.rglob("test_*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        module: list[str] = []
        for stmt in tree.body:
            if isinstance(stmt, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "pytestmark" for t in stmt.targets):
                module += _marks(stmt.value)
        rel = path.relative_to(REPO).as_posix()
        for stmt in tree.body:
            _collect(stmt, rel, module, out)
    return out


def _collect(stmt: ast.stmt, prefix: str, inherited: list[str], out: dict[str, list[str]]
             ) -> None:
    """Add the marked test functions of ``stmt`` (a function or a class) to ``out``."""
    if isinstance(stmt, ast.ClassDef) and stmt.name.startswith("Test"):
        own = inherited + [i for d in stmt.decorator_list for i in _marks(d)]
        for sub in stmt.body:
            _collect(sub, f"{prefix}::{stmt.name}", own, out)
    elif isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef)) \
            and stmt.name.startswith("test"):
        ids = inherited + [i for d in stmt.decorator_list for i in _marks(d)]
        if ids:
            out[f"{prefix}::{stmt.name}"] = sorted(set(ids))


def junit_results(path: Path) -> dict[str, str]:
    """``{node id without parameters: result}`` of a pytest JUnit XML file: ``failed`` when
    a case failed or erred, else ``passed`` when one passed, else ``skipped``."""
    out: dict[str, str] = {}
    rank = {"skipped": 0, "passed": 1, "failed": 2}
    for case in ET.parse(path).getroot().iter("testcase"):
        parts = (case.get("classname") or "").split(".")
        name = (case.get("name") or "").split("[")[0]
        # classname: tests.audit.test_audit or tests.audit.test_audit.TestClass
        cut = next((i for i, p in enumerate(parts) if p.startswith("test_")), len(parts) - 1)
        node = "/".join(parts[:cut + 1]) + ".py::" + "::".join(parts[cut + 1:] + [name])
        kids = {child.tag for child in case}
        result = ("failed" if kids & {"failure", "error"} else
                  "skipped" if "skipped" in kids else "passed")
        prev = out.get(node)
        if prev is None or rank[result] > rank[prev]:
            out[node] = result
    return out


def problems(reqs: list, marked: dict[str, list[str]],
             results: dict[str, str] | None = None) -> list[str]:
    """What makes the matrix fail: a marker naming an unknown id; a requirement with no
    test and no ``not_verified`` reason; one with both (the reason is stale); and with
    ``results`` (the runs' JUnit results), a requirement one of whose traced tests failed or
    was not run, or whose traced tests were all skipped: what shows it must have run and
    passed (IEC 61508-3 7.4.4.10: evidence of the tool's conformance, not of its tests'
    presence)."""
    known = {r.id for r in reqs}
    out = [f"{node}: unknown requirement {i}" for node, ids in sorted(marked.items())
           for i in ids if i not in known]
    shown = {i for ids in marked.values() for i in ids}
    for r in reqs:
        if r.id not in shown and not r.not_verified:
            out.append(f"{r.id}: no test shows it and no not_verified reason says why")
        if r.id in shown and r.not_verified:
            out.append(f"{r.id}: tests show it, but it is marked not verified")
    if results is None:
        return out
    for r in reqs:
        tests = sorted(n for n, ids in marked.items() if r.id in ids)
        got = {n: results.get(n, "not run") for n in tests}
        for n, result in got.items():
            if result in ("failed", "not run"):
                out.append(f"{r.id}: its traced test {n} {result}")
        if tests and all(v == "skipped" for v in got.values()):
            out.append(f"{r.id}: every traced test was skipped ({len(tests)})")
    return out


def matrix(reqs: list, marked: dict[str, list[str]], results: dict[str, str] | None
           ) -> str:
    """The matrix as Markdown: one row per requirement and test (``not run`` for a test
    without a result in ``results``; no result column without ``results``)."""
    lines = ["# Traceability matrix", "", "| requirement | test | result |", "|---|---|---|"]
    by_req: dict[str, list[str]] = {}
    for node, ids in marked.items():
        for i in ids:
            by_req.setdefault(i, []).append(node)
    for r in reqs:
        if r.not_verified:
            lines.append(f"| {r.id} | not verified: {r.not_verified} | |")
        for node in sorted(by_req.get(r.id, [])):
            result = "" if results is None else results.get(node, "not run")
            lines.append(f"| {r.id} | `{node}` | {result} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """The command line (module docstring); returns the exit code."""
    from fretc.qualification.catalogue import load_requirements

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--junit", type=Path, action="append", default=[],
                    help="a pytest JUnit XML file of the last results (repeatable)")
    ap.add_argument("-o", "--output", type=Path, help="write the matrix here")
    args = ap.parse_args(argv)
    reqs = list(load_requirements())
    marked = markers()
    results: dict[str, str] | None = None
    rank = {"skipped": 0, "passed": 1, "failed": 2}
    for path in args.junit:
        results = results or {}
        for node, result in junit_results(path).items():
            if rank[result] >= rank.get(results.get(node, "skipped"), 0):
                results[node] = result
    text = matrix(reqs, marked, results)
    if args.output:
        args.output.write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    found = problems(reqs, marked, results)
    for p in found:
        print(f"tor_matrix: {p}", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
