"""Witness traces of ``fretc check`` findings, as CSV files ``fretc audit`` reads directly.

A witness is a *finite* run, so it is built from the **ft** formulas (FRET's finite-trace
semantics, the one the audit's verdict uses) under FRET's trace model
(``compiler/evaluate.py``): Spot finds an infinite word of

Design notes: ARCHITECTURE.md, `check/witness.py`."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.check.atom_values import concrete_rows, free_atoms
from fretc.check.past_testers import with_testers
from fretc.check.solver import UNKNOWN
from fretc.check.stream_rows import trace_streams, with_stream_columns, with_stream_inputs
from fretc.common.outputs import output_folder, write_file
from fretc.common.textsafe import csv_line
from fretc.compiler import ir
from fretc.compiler.evaluate import INTERPRETED_FUNCTIONS, ft_at
from fretc.compiler.ir import LAST, Node, name_of
from fretc.compiler.printers import mangle, to_smv

if TYPE_CHECKING:
    from fretc.fretish.ast import Requirement
    from fretc.check.items import CheckItem
    from fretc.check.findings import CheckResult
    from fretc.check.checker import Checker

__all__ = ["trace_columns", "Judge", "finite_trace", "write_witnesses", "expected_verdicts",
           "read_expected"]

#: FRET's verdict of one requirement on a finite trace: ``judge(requirement, columns, n,
#: duration_ticks)`` -> ``"satisfied"``, ``"vacuous"``, ``"violated"`` or ``"unknown"``
#: (``columns``: FRET variable -> numpy array of ``n`` values; ``duration_ticks`` as
#: ``Formalization.ticks``). The audit's is :func:`fretc.monitors.interval.verdict_of`.
Judge = Callable[["Requirement", Mapping[str, np.ndarray], int, "int | None"], str]

_EXPECTED = re.compile(r"#\s*expected:\s*(.*)")


def formula_atoms(nodes: Sequence[Node]) -> list[Node]:
    """The atoms of the formulas ``nodes`` (propositions, comparisons, calls and FRET's
    temporal functions: what a witness trace gives a value), each once, in the order of a
    walk of the formulas."""
    out, seen = [], set()
    for f in nodes:
        for n in ir.walk(f):
            if n.op in ("ap", "cmp", "call", "past", "future") and n not in seen:
                seen.add(n)
                out.append(n)
    return out


def _absorbing_value(atom: Node) -> bool:
    if atom.op == "cmp":
        names = {name_of(n) for n in ir.walk(atom) if n.op == "var"}
        try:
            return bool(ft_at(atom, [{n: 0.0 for n in names}], 0))
        except Exception:
            return False
    return False


def _finite_model(nodes: Sequence[Node]) -> Node:
    absorbing = ir.and_all(*(a if _absorbing_value(a) else ir.not_(a)
                             for a in formula_atoms(nodes)))
    return ir.U(ir.not_(LAST), ir.and_(LAST, ir.X(ir.G(ir.and_(ir.not_(LAST), absorbing)))))


def finite_trace(checker: Checker, formulas: Sequence[Node], columns: dict[str, str],
                 length: int | None = None) -> Any:  # rows, None or UNKNOWN
    """A finite trace meeting the ft ``formulas`` (list of rows ``{variable: value}`` over
    ``columns``, name -> ``"bool"``/``"float"``), None when there is none, or UNKNOWN.
    ``length``: exactly that many ticks. Comparisons of one variable with constants get
    the numeric abstraction's numbers, the others z3's (:mod:`fretc.check.atom_values`).
    A FRET stream variable the formulas read (:mod:`fretc.check.stream_rows`) has its
    inputs as columns too, and its column is computed from them as the audit computes it."""
    streams = trace_streams(checker.items, columns)
    columns = with_stream_inputs(columns, streams)
    got = None
    if checker.uses_smt(formulas):  # past Spot's bounds: the pt monitors, when they take it
        got = checker.monitor_word(formulas, finite=True, length=length)
    if got is not None:
        ok, word = got
        if ok is not True:
            return ok if ok == UNKNOWN else None
        assert word is not None  # (the monitors found a word)
        letters = word[0]
    else:
        letters = _spot_trace(checker, formulas, length)
        if letters is None or letters == UNKNOWN:
            return letters
    cmp_atoms = {to_smv(a): a for name in checker.numeric.atoms
                 for a in checker.numeric.atoms[name]}
    rows = []
    for letter in letters:
        truth = {cmp_atoms[k]: v for k, v in letter.items() if k in cmp_atoms}
        numbers = checker.numeric.values(truth)
        row: dict[str, bool | float] = {}
        for name, kind in columns.items():
            if kind == "bool":  # a variable by FRET's name; a call by its text
                row[name] = bool(letter.get(mangle(name), letter.get(name, False)))
            else:
                row[name] = numbers.get(name, 0.0)
        rows.append(row)
    return concrete_rows(rows, letters, free_atoms(formulas, streams), streams)


def _spot_trace(checker, formulas: Sequence[Node], length: int | None):
    """The letters of a finite trace meeting the ft ``formulas`` by the LAST encoding of the
    module docstring (Spot, or z3 past its bounds), None or UNKNOWN. A derived past atom
    is its expansion over temporal testers (:func:`fretc.check.past_testers.with_testers`),
    so the letters give it its value."""
    extra = [_finite_model(formulas)]
    formulas, axioms = with_testers(formulas, LAST)
    extra += axioms
    if length is not None:
        at = LAST
        for _ in range(length - 1):
            at = ir.X(at)
        extra.append(at)
    ok, word = checker.sat_word(list(formulas) + extra)
    if ok is not True:
        return ok if ok == UNKNOWN else None
    prefix, cycle = word
    letters = []
    last_name = to_smv(LAST)
    k = 0
    seq = list(prefix)
    while True:
        letter = seq[k] if k < len(seq) else cycle[(k - len(seq)) % len(cycle)]
        letters.append(letter)
        if letter.get(last_name):
            return letters
        k += 1
        if k > len(seq) + len(cycle) + 1:  # pragma: no cover - the model forces LAST
            return None


def trace_columns(formulas: Sequence[Node], cols: dict[str, str] | None = None
                  ) -> dict[str, str]:
    """The columns a trace of ``formulas`` needs: name -> ``"bool"`` or ``"float"``, in
    order of first use (a variable used as a number anywhere is ``float``). An
    uninterpreted function application (``sqrt(weight)``, ``det_3x3(...)``) is a column
    named by its printed text, as the audit reads it (``compiler/evaluate.py``): numeric
    for a function of a term, boolean for one read as a condition. ``cols``: extended in
    place when given."""
    cols = {} if cols is None else cols
    for f in formulas:
        for n in ir.walk(f):
            if n.op == "var" or (n.op == "fn" and n.name not in INTERPRETED_FUNCTIONS):
                cols[name_of(n) if n.op == "var" else to_smv(n)] = "float"
            elif n.op == "ap" and n.name not in cols:
                cols[name_of(n)] = "bool"
            elif n.op == "call":
                cols.setdefault(to_smv(n), "bool")
    return cols


def _columns(items) -> dict[str, str]:
    return trace_columns([f for x in items for f in (x.phi_ft, x.phi)])


def expected_verdicts(items: Iterable[CheckItem], rows: list[dict], judge: Judge) -> dict[str, str]:
    """FRET's verdict of each item on ``rows`` (``satisfied``/``vacuous``/``violated``, or
    ``unknown`` where ``judge`` cannot decide), by ``judge`` (:data:`Judge`)."""
    n = len(rows)
    cols = {name: np.array([r[name] for r in rows]) for name in (rows[0] if rows else {})}
    out = {}
    for x in items:
        f, req = x.compiled.formalization, x.compiled.requirement
        assert f is not None and req is not None  # (an item is of a formalized requirement)
        try:
            out[x.id] = judge(req, cols, n, f.ticks)
        except (KeyError, ValueError):
            out[x.id] = "unknown"
    return out


def _cell(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if math.isfinite(v) and float(v).is_integer():
        return f"{v:.1f}"
    return repr(float(v))


def read_expected(path: str) -> dict[str, str]:
    """The ``# expected:`` verdicts of a witness CSV (requirement id -> verdict)."""
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        m = _EXPECTED.match(line)
        if m:
            return dict(p.strip().split("=", 1) for p in m.group(1).split(",") if "=" in p)
    return {}


def _write(path: Path, title: str, sources: list[str], rows: list[dict],
           expected: dict[str, str]) -> None:
    names = list(rows[0])
    lines = [f"# fretc check witness: {title}",
             "# replay: fretc audit " + " ".join(f"-r {s}" for s in sources) + f" {path}",
             "# one row per tick; expected verdicts (FRET finite-trace semantics):",
             "# expected: " + ", ".join(f"{k}={v}" for k, v in expected.items()),
             csv_line(names)]
    for r in rows:
        lines.append(",".join(_cell(r[n]) for n in names))
    write_file(path, "\n".join(lines) + "\n")  # (never through a link planted there)


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)[:60]


def write_witnesses(checker: Checker, result: CheckResult, witness_dir: str,
                    judge: Judge) -> None:
    """Write one witness CSV per finding (conflict, vacuity, unsatisfiable) and one for a
    consistent set, into ``witness_dir``; set ``Finding.witness``/``expected`` and
    ``result.witnesses``. ``judge`` gives the expected verdicts written in each file
    (:data:`Judge`)."""
    out = Path(output_folder(witness_dir))
    if not checker.items:
        return
    w = _Witnesses(checker, judge)
    serial = 0
    for finding in result.findings:
        if finding.kind not in ("conflict", "vacuous", "unsatisfiable"):
            continue
        plans = w.plans(finding)
        if not plans:
            continue
        best = w.best(plans)
        if best is None:
            finding.details["witness"] = "not built: no finite trace found in time"
            continue
        rows, expected, wrong, intended = best
        serial += 1
        path = out / f"{serial:02d}_{finding.kind}_{_safe('_'.join(finding.requirements))}.csv"
        _write(path, finding.message, w.sources, rows, expected)
        finding.witness = str(path)
        finding.expected = expected
        finding.details["witness_intended"] = intended
        finding.details["witness_shows_finding"] = not wrong
        if wrong:
            finding.details["witness_note"] = (
                "the witness shows the finding only in part: "
                + ", ".join(f"{k} is {expected.get(k)}, not {v}" for k, v in wrong.items()))
    for finding in result.findings:
        if finding.kind == "unrealizable" and finding.details.get("run"):
            serial += 1
            _controller_run(w, finding, out / f"{serial:02d}_unrealizable_"
                            f"{_safe('_'.join(finding.requirements))}.csv")
    if not any(f.severity == "error" for f in result.findings):
        rows = None
        if w.comps:
            rows = w.attempt(w.filler(w.comps[0]))
        if rows and rows != UNKNOWN:
            path = out / "00_consistent.csv"
            expected = expected_verdicts(w.items, rows, judge)
            _write(path, "a run meeting every requirement", w.sources, rows, expected)
            result.witnesses.append({"kind": "consistent", "path": str(path),
                                     "expected": expected})
    for f in result.findings:
        if f.witness:
            result.witnesses.append({"kind": f.kind, "path": f.witness,
                                     "expected": f.expected})


def _controller_run(w: _Witnesses, finding, path: Path) -> None:
    """The witness of an unrealizable set: the defeating inputs with a controller's best
    effort (:mod:`fretc.check.safety_game`); some requirement of the set is violated whatever
    the controller does, so on this run too."""
    blank = {name: (False if kind == "bool" else 0.0) for name, kind in w.cols.items()}
    rows = with_stream_columns([{**blank, **r} for r in finding.details["run"]], w.streams)
    expected = expected_verdicts(w.items, rows, w.judge)
    _write(path, finding.message, w.sources, rows, expected)
    finding.witness = str(path)
    finding.expected = expected
    shown = any(expected.get(i) == "violated" for i in finding.requirements)
    finding.details["witness_shows_finding"] = shown
    if not shown:
        finding.details["witness_note"] = ("the controller's run violates none of "
                                           + ", ".join(finding.requirements)
                                           + " under FRET's finite-trace semantics")


class _Witnesses:
    """Finite traces for the findings of one check: the requirement items, their columns,
    the groups and the requirement files (for the replay command)."""

    def __init__(self, checker, judge: Judge):
        self.checker = checker
        self.judge = judge
        self.items = checker.items
        self.by_id = {x.id: x for x in self.items}
        self.streams = trace_streams(self.items, _columns(self.items))
        self.cols = with_stream_inputs(_columns(self.items), self.streams)
        self.sources: list[str] = []
        for x in self.items:
            if x.compiled.entry.source not in self.sources:
                self.sources.append(x.compiled.entry.source)
        self.comps = checker.groups()

    @staticmethod
    def trig(x) -> list:
        return [x.trigger_ft] if x.trigger_ft is not None else []

    def filler(self, comp) -> list:
        """Formula variants for a group: a run meeting it, triggers firing (else not)."""
        phis = [x.phi_ft for x in comp]
        return [phis + [t for x in comp for t in self.trig(x)], phis]

    def one(self, variants, length=None):
        """Rows meeting the first satisfiable variant, None, or UNKNOWN (time budget)."""
        for formulas in variants:
            rows = finite_trace(self.checker, formulas, self.cols, length)
            if rows == UNKNOWN:
                return UNKNOWN
            if rows:
                return rows
        return None

    def attempt(self, variants):
        """Rows meeting ``variants`` (first that works) on its group, and the other
        groups filled with runs of the same length that meet them."""
        main = self.one(variants)
        if main in (None, UNKNOWN):
            return main
        names = {n for f in variants[-1] for n in ir.variables(f)}
        rows = [dict(r) for r in main]
        for comp in self.comps:
            if names.intersection(v for x in comp for v in x.variables):
                continue
            part = self.one(self.filler(comp), len(rows))
            if part in (None, UNKNOWN):
                continue  # left at false / 0
            own = {v for x in comp for v in x.variables}
            own |= {i for s in (self.streams.systems if self.streams else ())
                    if own & set(s.names) for i in s.inputs}
            for r, p in zip(rows, part):
                r.update({k: v for k, v in p.items() if k in own})
        return with_stream_columns(rows, self.streams)

    def plans(self, finding) -> list:
        """(formula variants, intended verdicts) that would show ``finding``, best first."""
        by_id, trig = self.by_id, self.trig
        if finding.kind == "unsatisfiable":
            x = by_id[finding.requirements[0]]
            return [([[ir.not_(x.phi_ft)] + trig(x), [ir.not_(x.phi_ft)]],
                     {x.id: "violated"})]
        subset = [by_id[i] for i in finding.subsets[0]] if finding.subsets else []
        if not subset:
            return []
        plans = []
        target = by_id[finding.details["requirement"]] if finding.kind == "vacuous" else None
        others = [y for y in subset if y is not target] or [target]
        for victim in reversed(others):  # the last member first
            keep = [y for y in subset if y is not victim]
            base = [y.phi_ft for y in keep] + [ir.not_(victim.phi_ft)]
            if target is not None and target is not victim:
                base += trig(target)
            trigs = [t for y in keep for t in trig(y)]
            intended = {y.id: "satisfied" for y in keep}
            intended[victim.id] = "violated"
            plans.append(([base + trigs, base], intended))
        return plans

    def best(self, plans):
        """(rows, expected, wrong, intended) of the plan whose trace shows most of its
        intended verdicts (the first that shows all), or None when no trace was found."""
        best = None
        for variants, intended in plans:
            rows = self.attempt(variants)
            if rows == UNKNOWN or not rows:
                continue
            expected = expected_verdicts(self.items, rows, self.judge)
            wrong = {k: v for k, v in intended.items() if expected.get(k) != v}
            if best is None or len(wrong) < len(best[2]):
                best = (rows, expected, wrong, intended)
            if not wrong:
                break
        return best
