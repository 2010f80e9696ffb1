"""Requirements-based tests (``fretc testgen``): for every coverage obligation of a set of
requirements (:mod:`fretc.compiler.coverage`) that some finite trace meets, a trace meeting
it, and for every test the expected verdict of every requirement of the set on it.

Design notes: ARCHITECTURE.md, `testing/generate.py`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from fretc.check.budget import Budget
from fretc.common.outputs import output_folder, write_file
from fretc.common.textsafe import csv_line, visible
from fretc.check.checker import Checker
from fretc.check.items import CheckItem, make_item
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.check.stream_rows import (TraceStreams, trace_streams, with_stream_columns,
                                     with_stream_inputs)
from fretc.check.witness import finite_trace, trace_columns
from fretc.compiler import ir
from fretc.compiler.build import Compiled
from fretc.compiler.coverage import Obligation, obligations
from fretc.compiler.semantics import Formalization, SemanticsError, formalize
from fretc.fretish import ast as A
from fretc.logs.csv.source import SAMPLED_MARK, column_name_problem
from fretc.monitors.coverage import exercised
from fretc.monitors.interval import verdict_of
from fretc.monitors.judge3 import verdict_under_nan

__all__ = ["Generated", "TestCase", "generate", "column_kinds", "expected_of", "covered_by",
           "separating_trace", "Finder", "SPURIOUS", "write_tests"]

#: :meth:`Finder.find`'s answer when the engines found traces the judge did not confirm
SPURIOUS = "spurious"

_PAIRS = (("satisfied", "violated"), ("satisfied", "vacuous"), ("violated", "satisfied"),
          ("vacuous", "satisfied"), ("violated", "vacuous"), ("vacuous", "violated"))


@dataclass
class TestCase:
    """One generated test: ``rows`` (one mapping FRET variable -> value per tick),
    ``covers`` (``(requirement id, obligation id, tick)`` it exercises), ``expected``
    (requirement id -> verdict) and ``origin`` (the obligation it was generated for); with
    bindings (:func:`fretc.testing.mcap_log.bind_tests`) ``log`` (its MCAP file name or
    None), ``log_why`` (why none) and ``adjusted`` (variables the bindings gave other
    values)."""

    rows: list[dict[str, Any]]
    covers: list[tuple[str, str, int | None]] = field(default_factory=list)
    expected: dict[str, str] = field(default_factory=dict)
    origin: tuple[str, str] = ("", "")
    log: str | None = None
    log_why: str | None = None
    adjusted: list[str] = field(default_factory=list)


@dataclass
class Generated:
    """What :func:`generate` found: the kept ``tests``, the ``unmeetable`` and ``unknown``
    obligations as ``(obligation, reason)``, and every obligation of the set
    (``obligations``: requirement id -> list)."""

    tests: list[TestCase]
    unmeetable: list[tuple[Obligation, str]]
    unknown: list[tuple[Obligation, str]]
    obligations: dict[str, list[Obligation]]


def _formal(c: Compiled) -> tuple[A.Requirement, Formalization]:
    """``c``'s parsed requirement and formalization (a test is generated of formalized
    requirements only: ``ValueError`` for another)."""
    if c.requirement is None or c.formalization is None:
        raise ValueError(f"{c.id} has no formalization")
    return c.requirement, c.formalization


#: rows that accept(rows) confirms a trace meets what was asked
Accept = Callable[[list[dict[str, Any]]], bool]


def column_kinds(compiled: Sequence[Compiled]) -> dict[str, str]:
    """FRET variable -> ``"bool"`` or ``"float"`` over the ft formulas of ``compiled``, in
    order of first use (:func:`fretc.check.witness.trace_columns`: a variable used as a
    number anywhere is ``float``; an uninterpreted function is its own column), then the
    variables the FRET stream variables they read are computed from
    (:func:`fretc.check.stream_rows.with_stream_inputs`)."""
    cols = trace_columns([_formal(c)[1].ft for c in compiled])
    return with_stream_inputs(cols, trace_streams(compiled, cols))


def _columns(rows: list[dict[str, Any]], kinds: dict[str, str]) -> dict[str, np.ndarray]:
    return {k: np.array([r[k] for r in rows], dtype=bool if t == "bool" else float)
            for k, t in kinds.items()}


def expected_of(compiled: Sequence[Compiled], rows: list[dict[str, Any]], kinds: dict[str, str]
                ) -> dict[str, str]:
    """The audit's verdict of every requirement of ``compiled`` on ``rows``
    (:func:`fretc.monitors.judge3.verdict_under_nan`: FRET's interval verdict, under
    fretc's NaN rule where a comparison reads NaN, as ``x / 0`` does)."""
    cols = _columns(rows, kinds)
    out = {}
    for c in compiled:
        req, f = _formal(c)
        out[c.id] = verdict_under_nan(req, f.pt, cols, len(rows), f.ticks)
    return out


def covered_by(compiled: Sequence[Compiled], obs: dict[str, list[Obligation]],
               rows: list[dict[str, Any]], kinds: dict[str, str],
               only: set[tuple[str, str]] | None = None) -> list[tuple[str, str, int | None]]:
    """``(requirement id, obligation id, tick)`` of every obligation ``rows`` exercises
    (``only``: of these ``(requirement id, obligation id)`` alone)."""
    cols = _columns(rows, kinds)
    out: list[tuple[str, str, int | None]] = []
    for c in compiled:
        mine = [o for o in obs[c.id] if only is None or (c.id, o.id) in only]
        if not mine:
            continue
        req, f = _formal(c)
        got = exercised(mine, req, cols, len(rows), f.ticks)
        out.extend((c.id, o.id, e.tick) for o, e in zip(mine, got) if e.met)
    return out


def _audit_agrees(req: A.Requirement, f: Formalization, cols: dict[str, np.ndarray],
                  n: int) -> bool:
    """Whether the audit's verdict of ``req`` on the trace (under fretc's NaN rule) is the
    interval verdict an obligation is judged by: a trace whose obligation rests on a
    comparison reading NaN (``x / 0``) is not confirmed."""
    return (verdict_under_nan(req, f.pt, cols, n, f.ticks)
            == verdict_of(req, cols, n, f.ticks))


def _variant(c: Compiled, req: A.Requirement, suffix: str) -> Compiled:
    entry = dataclasses.replace(c.entry, id=f"{c.id}~{suffix}", requirement=req)
    return Compiled(entry, formalize(req, c.entry.tick_period))


def _classes(item: CheckItem, verdict: str) -> list[ir.Node]:
    phi, trig = item.phi_ft, item.trigger_ft
    if verdict == "violated":
        return [ir.not_(phi)]
    if trig is None:
        return [phi]
    return [phi, trig if verdict == "satisfied" else ir.not_(trig)]


class Finder:
    """The queries of one requirement's obligations (module docstring) in one Spot worker
    (``worker``); ``kinds``: FRET variable -> ``"bool"``/``"float"`` of the rows built;
    ``streams``: the set's FRET stream variables, whose columns every trace found computes
    (:func:`fretc.check.stream_rows.with_stream_columns`)."""

    def __init__(self, worker: SpotWorker, kinds: dict[str, str],
                 streams: TraceStreams | None = None):
        self.worker = worker
        self.kinds = kinds
        #: the FRET stream variables of the whole set (a query's items may be of another
        #: component, whose export does not define them): computed in every trace
        self.streams = streams

    def _rows(self, items: list[CheckItem], queries: list[list[ir.Node]], accept: Accept
              ) -> tuple[Any, str]:  # (rows, None, UNKNOWN or SPURIOUS; the engine)
        ck = Checker(items, self.worker)
        engine = "z3 or the pt monitors" if ck.uses_smt(queries[0]) else "Spot"
        unknown = spurious = False
        for q in queries:
            got = finite_trace(ck, q, self.kinds)
            if got == UNKNOWN:
                unknown = True
            elif got:
                rows = with_stream_columns(_complete(got, self.kinds), self.streams)
                if accept(rows):
                    return rows, engine
                spurious = True
        why = (self.worker.failures[-1] if self.worker.failures else "") or \
            (ck.smt.failures[-1] if ck.smt.failures else "")
        if spurious and not unknown:
            return SPURIOUS, engine
        return (UNKNOWN if unknown else None), (engine + (f": {why}" if why else ""))

    def find(self, c: Compiled, ob: Obligation, accept: Accept) -> tuple[Any, str]:
        """Rows meeting ``ob`` (every variable of :attr:`kinds`) that ``accept(rows)``
        confirms, None (no finite trace), UNKNOWN or SPURIOUS (traces found, none
        confirmed); and the engine's words."""
        base = make_item(0, c)
        if ob.kind == "threshold":
            assert ob.atom is not None  # (a threshold obligation has its comparison)
            atom = ob.atom if ob.side else A.Unary("!", ob.atom)
            aux_req = A.Requirement(text="", component="c", timing=A.Timing("eventually"),
                                    response=atom)
            aux = make_item(1, _variant(c, aux_req, "seen"))
            trig = [base.trigger_ft] if base.trigger_ft is not None else []
            queries = [[base.phi_ft] + trig + [aux.phi_ft], [base.phi_ft, aux.phi_ft],
                       [aux.phi_ft]]
            return self._rows([base, aux], queries, accept)
        assert ob.variant is not None  # (an obligation other than a threshold has it)
        other = make_item(1, _variant(c, ob.variant, "variant"))
        queries = [_classes(base, v1) + _classes(other, v2) for v1, v2 in _PAIRS]
        return self._rows([base, other], queries, accept)


def separating_trace(finder: Finder, c: Compiled, other: A.Requirement
                     ) -> tuple[Any, str]:
    """A trace on which ``c`` and the requirement ``other`` (same tick period) get different
    verdicts from the audit's judge: rows, None (no finite trace separates their verdict
    classes: equivalent as far as those classes go), UNKNOWN or SPURIOUS; and the engine."""
    v = _variant(c, other, "other")
    kinds = finder.kinds
    (req, f), (_, fv) = _formal(c), _formal(v)

    def accept(rows: list[dict[str, Any]]) -> bool:
        cols = _columns(rows, kinds)
        return (verdict_of(req, cols, len(rows), f.ticks)
                != verdict_of(other, cols, len(rows), fv.ticks))

    ob = Obligation(c.id, "other", "other", "", other, fv.ticks)
    return finder.find(c, ob, accept)


def _complete(rows: list[dict[str, Any]], kinds: dict[str, str]) -> list[dict[str, Any]]:
    return [{k: r.get(k, False if t == "bool" else 0.0) for k, t in kinds.items()}
            for r in rows]


def _candidates(compiled: Sequence[Compiled], obs: dict[str, list[Obligation]],
                kinds: dict[str, str], budget: Budget | None, fork: bool
                ) -> tuple[list[TestCase], list[tuple[Obligation, str]],
                           list[tuple[Obligation, str]]]:
    """One checked trace per meetable obligation; the unmeetable and unknown ones."""
    found: list[TestCase] = []
    unmeetable: list[tuple[Obligation, str]] = []
    unknown: list[tuple[Obligation, str]] = []
    left = {(c.id, o.id) for c in compiled for o in obs[c.id]}
    with SpotWorker(budget or Budget(), fork=fork) as worker:
        finder = Finder(worker, kinds, trace_streams(compiled, kinds))
        for c in compiled:
            for ob in obs[c.id]:
                if (c.id, ob.id) not in left:
                    continue  # an earlier trace meets it already

                def accept(rows: list[dict[str, Any]], c: Compiled = c,
                           ob: Obligation = ob) -> bool:
                    req, f = _formal(c)
                    cols, n = _columns(rows, kinds), len(rows)
                    return exercised([ob], req, cols, n, f.ticks)[0].met and (
                        _audit_agrees(req, f, cols, n))

                try:
                    rows, engine = finder.find(c, ob, accept)
                except SemanticsError as exc:
                    unknown.append((ob, f"the variant does not formalize: {exc}"))
                    continue
                if rows is None:
                    unmeetable.append((ob, f"no finite trace meets it ({engine})"))
                    continue
                if rows == UNKNOWN:
                    unknown.append((ob, f"not decided within the budget ({engine})"))
                    continue
                if rows == SPURIOUS:
                    unknown.append((ob, f"{engine}'s traces do not meet it by the audit's "
                                        "judge (an abstraction of the atoms was spurious)"))
                    continue
                cov = covered_by(compiled, obs, rows, kinds, left)
                left.difference_update((r, o) for r, o, _ in cov)
                found.append(TestCase(rows, cov, origin=(c.id, ob.id)))
    return found, unmeetable, unknown


def _cover(found: list[TestCase]) -> list[TestCase]:
    """Greedy set cover of the obligations the candidates meet (ties: the earlier)."""
    left = {(r, o) for t in found for r, o, _ in t.covers}
    kept = []
    while left:
        best = max(found, key=lambda t: len(left & {(r, o) for r, o, _ in t.covers}))
        gain = left & {(r, o) for r, o, _ in best.covers}
        if not gain:
            break
        kept.append(best)
        left -= gain
    return kept


def _drop_redundant(tests: list[TestCase]) -> list[TestCase]:
    """``tests`` without those whose every obligation the others cover (the last first)."""
    kept = list(tests)
    for t in reversed(tests):
        others = {(r, o) for u in kept if u is not t for r, o, _ in u.covers}
        if {(r, o) for r, o, _ in t.covers} <= others:
            kept.remove(t)
    return kept


def generate(compiled: Sequence[Compiled], *, budget: Budget | None = None,
             fork: bool = True, kinds: frozenset[str] | None = None) -> Generated:
    """The tests of ``compiled`` (formalized, not free-form requirements of one set): see the
    module docstring. ``budget``: the engines' work budget per query
    (:class:`fretc.check.budget.Budget`); ``fork``: run Spot in a worker process;
    ``kinds``: only the obligations of these kinds (:class:`Obligation`'s ``kind``; None:
    all), e.g. ``{"atom"}`` for FLIP's one obligation per atom and value."""
    compiled = [c for c in compiled if c.formalization is not None]
    obs = {}
    for c in compiled:
        req, f = _formal(c)
        obs[c.id] = [o for o in obligations(c.id, req, f.ticks)
                     if kinds is None or o.kind in kinds]
    cols = column_kinds(compiled)
    found, unmeetable, unknown = _candidates(compiled, obs, cols, budget, fork)
    tests = _cover(found)
    for t in tests:  # every obligation each kept test exercises, not only its new ones
        t.covers = covered_by(compiled, obs, t.rows, cols)
    tests = _drop_redundant(tests)
    for t in tests:
        t.expected = expected_of(compiled, t.rows, cols)
    return Generated(tests, unmeetable, unknown, obs)


def _cell(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    return repr(float(v))


def _obligation_json(ob: Obligation, reason: str | None = None) -> dict[str, Any]:
    out = {"requirement": ob.requirement, "obligation": ob.id, "kind": ob.kind,
           "description": ob.description}
    if reason is not None:
        out["reason"] = reason
    return out


def write_tests(gen: Generated, out_dir: str, sources: Sequence[str],
                period: Fraction | None = None, bindings: str | None = None) -> dict[str, Any]:
    """Write ``DIR/T01.csv``... (one per test: comment lines, the first one
    :data:`fretc.logs.csv.source.SAMPLED_MARK` so that an audit with binding files reads the
    columns as the FRET variables they are; then a header row, ``time`` (tick ``k`` at ``k *
    period`` seconds, when ``period`` is given) and the FRET variables, one row per tick) and
    ``DIR/tests.json``; return the JSON document written (format in the module docstring of
    :mod:`fretc.cli.testgen`). ``sources``: the requirement files, for the replay line;
    ``bindings``: the binding file the tests' MCAP logs were written with
    (:func:`fretc.testing.mcap_log.bind_tests`), or None. Ids and paths in the comment lines
    are written visible (:func:`fretc.common.textsafe.visible`: a line break in an id
    cannot end its line).

    Raises:
        ValueError: a variable a CSV trace cannot carry as a column
            (:func:`fretc.logs.csv.source.column_name_problem`); nothing is written."""
    from pathlib import Path
    import json

    out = Path(out_dir)
    for t in gen.tests:  # every variable a column the audit reads back as that variable
        for n in t.rows[0] if t.rows else ():
            why = column_name_problem(n)
            if why is not None:
                raise ValueError(f"the variable {visible(n)!r} cannot be a column of a test's "
                                 f"CSV trace: {why}; rename it")
    output_folder(out)
    replay = "fretc audit " + " ".join(f"-r {visible(s)}" for s in sources)
    tests = []
    for k, t in enumerate(gen.tests, 1):
        name = f"T{k:02d}"
        names = list(t.rows[0])
        lines = [f"{SAMPLED_MARK}: fretc testgen test {name}, generated for "
                 f"{visible(t.origin[0])} {visible(t.origin[1])}; FRET variables, one row per "
                 "tick", f"# replay: {replay} {visible(out / (name + '.csv'))}",
                 "# one row per tick; expected verdicts (FRET finite-trace semantics):",
                 "# expected: " + ", ".join(f"{visible(r)}={v}" for r, v in t.expected.items()),
                 csv_line((["time"] if period else []) + names)]
        lines += [",".join(([f"{float(i * period):.9f}"] if period else [])
                           + [_cell(r[n]) for n in names]) for i, r in enumerate(t.rows)]
        write_file(out / f"{name}.csv", "\n".join(lines) + "\n")  # (never through a link)
        tests.append({"id": name, "trace": f"{name}.csv", "ticks": len(t.rows),
                      "generated_for": {"requirement": t.origin[0], "obligation": t.origin[1]},
                      "covers": [{"requirement": r, "obligation": o, "tick": tick}
                                 for r, o, tick in t.covers],
                      "expected": dict(t.expected)})
        if bindings is not None:
            tests[-1].update({"log": t.log, "log_not_written": t.log_why,
                              "adjusted": list(t.adjusted)})
    doc = {"requirements": list(sources), **({"bindings": bindings} if bindings else {}),
           "tests": tests,
           "obligations": [_obligation_json(o) for obs in gen.obligations.values()
                           for o in obs],
           "unmeetable": [_obligation_json(o, why) for o, why in gen.unmeetable],
           "unknown": [_obligation_json(o, why) for o, why in gen.unknown]}
    write_file(out / "tests.json", json.dumps(doc, indent=2) + "\n")
    return doc
