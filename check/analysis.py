"""``fretc check``: consistency, non-vacuity, minimal conflicts and redundancy of a set of
requirements, decided by Spot on their formulas (../shared/DESIGN.md, "Check requirements before
runs"); for queries with a bound past :data:`SPOT_MAX_BOUND`, by fixed points over the
requirements' pt monitors (:mod:`fretc.check.monitor_sat`) when every formula has one, else by z3
(:mod:`fretc.check.smt`).

Design notes: ARCHITECTURE.md, `check/analysis.py`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TYPE_CHECKING

from fretc.compiler import ir
from fretc.check.budget import Budget
from fretc.check.checker import ENGINES, MUS_BUDGET, SPOT_MAX_BOUND, Checker
from fretc.check.findings import CheckResult, Finding
from fretc.check.findings import ids as _ids
from fretc.check.findings import subsets_text
from fretc.check.items import CheckItem, atom_variables, make_item
from fretc.check.streams import CheckStream, check_streams, stream_atoms
from fretc.check.solver import UNKNOWN, SpotWorker

if TYPE_CHECKING:
    from fretc.check.witness import Judge
    from fretc.compiler.build import Compiled

#: the stages of a group's check, in order (each requirement alone, the set, each
#: requirement's non-vacuity, each one's redundancy), as :data:`Progress` names them
STAGES = ("alone", "set", "vacuity", "redundancy")

#: ``progress(stage, at, total, group, groups)`` (:func:`check_requirements`)
Progress = Callable[[str, int, int, int, int], None]

__all__ = ["STAGES", "Progress", "CheckItem", "CheckResult", "Finding", "Checker",
           "check_requirements", "atom_variables", "make_item", "ENGINES", "SPOT_MAX_BOUND"]

#: why an answer is unknown, in the findings (the notes give each query's reason)
WHY_UNKNOWN = ("the query ran past its work or memory budget (--budget, --memory-budget) or "
               "the solver could not take it (see the notes)")


def _where(items: Sequence[CheckItem]) -> str:
    return ", ".join(f"{x.id} ({x.location})" for x in items)


def _tri(ans) -> object:
    return "unknown" if ans == UNKNOWN else ans


# --------------------------------------------------------------------------- entry point
def check_requirements(compiled: Sequence[Compiled], *, budget: Budget | None = None,
                       mus_budget: int = MUS_BUDGET, redundancy: bool = True,
                       vacuity: bool = True, witness_dir: str | None = None,
                       inputs: Sequence[str] | None = None,
                       outputs: Sequence[str] | None = None,
                       worker: SpotWorker | None = None,
                       witness_judge: Judge | None = None, engine: str = "auto",
                       deadline: float | None = None,
                       progress: Progress | None = None) -> CheckResult:
    """Check compiled requirements (:class:`fretc.compiler.build.Compiled`, in file order).

    ``budget``: each query's work and memory budgets (:class:`fretc.check.budget.Budget`; default
    the defaults). ``mus_budget``: subset checks per enumeration of minimal subsets.
    ``deadline``: the run's wall-clock limit (a ``time.monotonic()`` value): past it the
    run stops with :class:`fretc.check.budget.RunStopped` (never an answer changed). ``witness_dir``: write witness CSVs there
    (:mod:`fretc.check.witness`), their expected verdicts given by ``witness_judge``
    (:data:`fretc.check.witness.Judge`; required with ``witness_dir``: the audit's
    evidence engine lives in a layer above, ``fretc check`` passes
    :func:`fretc.monitors.interval.verdict_of`). ``inputs``/``outputs``: FRET variable names; when
    either is given, realizability is checked too (:mod:`fretc.check.realizability`).
    Requirements that failed to formalize are listed in ``input_errors``; free-form ones
    and probability requirements (a bound at each trigger, never a property of every run)
    are skipped with a note. ``engine``: one of :data:`ENGINES` (satisfiability queries;
    realizability: :mod:`fretc.check.safety_game` for safety requirements unless ``spot``).
    ``progress``: called before each query of the stages of :data:`STAGES` (a requirement
    of a stage: before its query), as ``progress(stage, at, total, group, groups)``
    (counts from 1; ``fretc check`` shows it on a terminal: the redundancy stage of a
    group of 57 requirements takes about 4 minutes).
    Raises ``ValueError`` for another engine.
    """
    if witness_dir is not None and witness_judge is None:
        raise TypeError("check_requirements: witness_dir needs a witness_judge "
                        "(check.witness.Judge)")
    result = CheckResult()
    items: list[CheckItem] = []
    for c in compiled:
        if c.error is not None:
            result.input_errors.append(str(c.error))
        elif c.freeform:
            result.notes.append(f"{c.id} ({c.location()}): free-form, not checked")
        elif c.probability is not None:  # FRET 3.1: a bound at each trigger, not every run
            b = c.probability
            result.notes.append(
                f"{c.id} ({c.location()}): 'with probability {b.op} {b.text}' bounds the "
                "chance of each trigger's obligation, which no single run satisfies or "
                "violates: not checked with the requirements every run must satisfy (judge "
                "it over runs: fretc audit of several logs, fretc estimate)")
        else:
            items.append(make_item(len(items), c))
    own = worker is None
    if worker is None:
        worker = SpotWorker(budget, deadline=deadline)
    try:
        checker = Checker(items, worker, mus_budget, engine=engine)
        streams = check_streams(items)
        _run(checker, result, vacuity=vacuity, redundancy=redundancy,
             progress=progress or _no_progress, streams=streams)
        if inputs is not None or outputs is not None:
            from fretc.check.realizability import check_realizability  # lazy: numpy, if asked
            result.realizability = check_realizability(checker, result, inputs or [],
                                                       outputs or [], streams)
        _link_findings(result)
        if witness_dir is not None:
            from fretc.check.witness import write_witnesses  # lazy: numpy, if asked
            assert witness_judge is not None  # (refused above)
            write_witnesses(checker, result, witness_dir, witness_judge)
            _stream_witness_note(result, streams)
        _figures(checker, worker, result)
    finally:
        if own:
            worker.close()
    return result


def _stream_witness_note(result: CheckResult, streams: dict[str, CheckStream]) -> None:
    """The note of witnesses written for requirements reading FRET stream variables
    (:mod:`fretc.check.streams`): their columns are computed from the variables their
    definitions read (:mod:`fretc.check.stream_rows`), as the audit computes them."""
    if streams and (result.witnesses or any(f.witness for f in result.findings)):
        result.notes.append(
            "the witnesses' columns of the stream variable" + "s" * (len(streams) > 1) + " "
            + ", ".join(sorted(streams)) + " are computed from the columns of the variables "
            "their definitions read, as fretc audit computes them again when it replays a "
            "witness (the checks read a comparison reading one as an independent "
            "proposition: a finding whose witness does not show it says so)")


def _figures(checker: Checker, worker: SpotWorker, result: CheckResult) -> None:
    """The run's query counts and the notes on what stayed unknown and why."""
    result.queries = checker.queries
    result.unknown_queries = worker.spent
    result.smt_queries = checker.smt_queries
    result.monitor_queries = checker.monitor_queries
    # a query the monitors left unknown and z3 was then asked is one query
    smt_failures = checker.smt.failures + checker.smt_fallback.failures
    result.unknown_queries += (checker.smt.spent + checker.smt_fallback.spent
                               - checker.fallbacks)
    if smt_failures:
        result.notes.append(f"z3 left {len(smt_failures)} queries unknown, e.g. "
                            f"{smt_failures[0]}")
    if checker.not_tried:
        result.notes.append(
            f"{checker.spent} queries spent their whole work budget, so "
            f"{checker.not_tried} later queries on the same requirements were not tried "
            "and are unknown (the run ends in bounded time; a larger --budget tries "
            "them)")
    if worker.failures:
        result.notes.append(f"{len(worker.failures)} queries got no answer from Spot or "
                            f"the pt monitors (unknown), e.g. {worker.failures[0]}"
                            + (f"; z3 answered {checker.rescued} of them"
                               if checker.rescued else ""))


def _no_progress(stage: str, done: int, total: int, group: int, groups: int) -> None:
    """A :data:`Progress` that shows nothing."""


def _run(ck: Checker, result: CheckResult, *, vacuity: bool, redundancy: bool,
         progress: Progress, streams: dict[str, CheckStream] | None = None) -> None:
    status: dict[int, dict[str, Any]] = {x.index: {"id": x.id, "source": x.compiled.entry.source,
                        "line": x.compiled.entry.line, "text": x.compiled.text,
                        "group": None, "satisfiable": None, "non_vacuous": None,
                        "redundant": None, "findings": []} for x in ck.items}
    # (an atom reading a FRET stream variable: its reason names the stream)
    forms = [f for x in ck.items for f in (x.phi, x.trigger, x.phi_ft, x.trigger_ft) if f]
    why_of = dict(ck.numeric.uninterpreted())
    why_of.update(stream_atoms(forms, streams or {}))
    for name, why in sorted(why_of.items()):
        result.abstractions.append({"atom": name, "why": why})
    comps = ck.groups()
    for k, comp in enumerate(comps):
        result.groups.append(_ids(comp))
        for x in comp:
            status[x.index]["group"] = k

        def say(stage: str, done: int, total: int, k: int = k) -> None:
            progress(stage, done, total, k + 1, len(comps))

        _check_group(ck, comp, status, result, vacuity, redundancy, say)
    result.requirements = [status[x.index] for x in ck.items]


def _link_findings(result: CheckResult) -> None:
    """Each requirement's status lists the indexes of the findings naming it (those of
    realizability too: ``fretc report --check`` shows them on the requirement's row)."""
    for s in result.requirements:
        s["findings"] = []
    for n, f in enumerate(result.findings):
        for rid in f.requirements:
            for s in result.requirements:
                if s["id"] == rid:
                    s["findings"].append(n)


def _check_group(ck: Checker, comp: list[CheckItem], status: dict,
                     result: CheckResult, vacuity: bool, redundancy: bool,
                     say: Callable[[str, int, int], None]) -> None:
    """Check one group (requirements sharing variables): each requirement alone, the
    set, then (when the set is satisfiable) non-vacuity and redundancy; findings and notes
    go to ``result``, per-requirement answers to ``status``."""
    alone_bad = _check_alone(ck, comp, status, result, say)
    say("set", 1, 1)
    if not _check_set(ck, comp, status, result, alone_bad):
        return
    if vacuity:
        _check_vacuity(ck, comp, status, result, say)
    if redundancy:
        _check_redundancy(ck, comp, status, result, say)


def _check_alone(ck: Checker, comp: list[CheckItem], status: dict,
                 result: CheckResult, say: Callable[[str, int, int], None]) -> list:
    """Satisfiability of each requirement on its own; returns the unsatisfiable ones."""
    alone_bad = []
    for i, x in enumerate(comp):
        say("alone", i + 1, len(comp))
        ans = ck.sat([x.phi])
        status[x.index]["satisfiable"] = _tri(ans)
        if ans is False:
            alone_bad.append(x)
            result.findings.append(Finding(
                "unsatisfiable", "error", [x.id],
                f"{x.id} ({x.location}) is unsatisfiable on its own: no run meets it",
                subsets=[[x.id]]))
        elif ans == UNKNOWN:
            result.findings.append(Finding(
                "unknown", "unknown", [x.id],
                f"satisfiability of {x.id} ({x.location}) unknown: " + WHY_UNKNOWN))
    return alone_bad


def _check_set(ck: Checker, comp: list[CheckItem], status: dict, result: CheckResult,
               alone_bad: list) -> bool:
    """Satisfiability of the group (minimal conflicting subsets when it is not);
    True when it is satisfiable (the later checks are meaningful)."""
    whole = ck.sat([x.phi for x in comp]) if len(comp) > 1 else ck.sat([comp[0].phi])
    if len(comp) > 1 and whole is False and not alone_bad:
        found = ck.minimal_subsets(comp, [], lambda s: _neg(ck.sat([y.phi for y in s])),
                                   known_bad=True)
        names = [_ids(s) for s in found.subsets]
        involved = sorted({i for s in names for i in s},
                          key=lambda i: [x.id for x in comp].index(i))
        msg = ("the requirements cannot all hold: "
               + subsets_text(names, found.standing, "conflicting subset")
               + (f" (enumeration cut by its budget of {ck.mus_budget} subset checks: there "
                  "may be more)" if found.cut else "")
               + (" (some subset checks were unknown)" if found.unknown else ""))
        result.findings.append(Finding("conflict", "error", involved, msg, subsets=names,
                                       standing=found.standing, cut=found.cut,
                                       details={"locations": {
                                           x.id: x.location for x in comp
                                           if x.id in involved}}))
    elif len(comp) > 1 and whole == UNKNOWN:
        result.findings.append(Finding(
            "unknown", "unknown", _ids(comp),
            "satisfiability of the set " + ", ".join(_ids(comp)) + " unknown: " + WHY_UNKNOWN))
    if whole is not True:
        for x in comp:
            if whole is False:
                status[x.index]["non_vacuous"] = None
        result.notes.append("group " + ", ".join(_ids(comp)) + ": non-vacuity and "
                            "redundancy not checked ("
                            + ("the requirements conflict)" if whole is False else
                               "the satisfiability of the set is unknown)"))
        return False
    return True


def _check_vacuity(ck: Checker, comp: list[CheckItem], status: dict,
                   result: CheckResult, say: Callable[[str, int, int], None]) -> None:
    """Can each requirement's trigger fire (its scope be entered) in a run meeting all?"""
    for i, x in enumerate(comp):
        say("vacuity", i + 1, len(comp))
        if x.trigger is None:
            continue
        ans = ck.sat([y.phi for y in comp], [x.trigger])
        status[x.index]["non_vacuous"] = _tri(ans)
        if ans is True:
            continue
        if ans == UNKNOWN:
            result.findings.append(Finding(
                "unknown", "unknown", [x.id],
                f"non-vacuity of {x.id} ({x.location}) unknown: " + WHY_UNKNOWN))
            continue
        found = ck.minimal_subsets(
            comp, [x], lambda s, x=x: _neg(ck.sat([y.phi for y in s] + [x.trigger])),  # type: ignore[misc]  # (x=x: this x)
            known_bad=True)
        names = [_ids(s) for s in found.subsets]
        if names and names[0] == [x.id]:
            msg = (f"{x.id} ({x.location}) can only be satisfied vacuously: its scope is "
                   "never entered or its trigger never fires with room for the response "
                   "in any run that meets it")
        else:
            msg = (f"{x.id} ({x.location}) can only be satisfied vacuously in the presence"
                   " of the others: no run meeting all requirements enters its scope and "
                   "fires its trigger; "
                   + subsets_text(names, found.standing, "set forcing this")
                   + (f" (enumeration cut by its budget of {ck.mus_budget} subset checks)"
                      if found.cut else "")
                   + (" (some subset checks were unknown)" if found.unknown else ""))
        involved = [x.id] + sorted({i for s in names for i in s if i != x.id})
        result.findings.append(Finding("vacuous", "error", involved, msg, subsets=names,
                                       standing=found.standing, cut=found.cut,
                                       details={"requirement": x.id}))


def _check_redundancy(ck: Checker, comp: list[CheckItem], status: dict,
                      result: CheckResult, say: Callable[[str, int, int], None]) -> None:
    """Is each requirement implied by the others of its group?"""
    for i, x in enumerate(comp):
        say("redundancy", i + 1, len(comp))
        others = [y.phi for y in comp if y is not x]
        ans = ck.sat(others, [ir.not_(x.phi)], word=False)
        status[x.index]["redundant"] = _tri(not ans) if ans in (True, False) else "unknown"
        if ans == UNKNOWN:
            result.findings.append(Finding(
                "unknown", "warning", [x.id],
                f"redundancy of {x.id} ({x.location}) unknown: " + WHY_UNKNOWN))
        if ans is False:
            if others:
                msg = (f"{x.id} ({x.location}) is implied by the others of its group ("
                       + ", ".join(_ids([y for y in comp if y is not x])) + ")")
            else:
                msg = f"{x.id} ({x.location}) holds on every run (on infinite traces)"
            result.findings.append(Finding("redundant", "warning", [x.id], msg,
                                           details={"implied_by": _ids(
                                               [y for y in comp if y is not x])}))


def _neg(ans):
    """sat answer -> 'bad' answer (unsatisfiable is bad)."""
    if ans == UNKNOWN:
        return UNKNOWN
    return not ans
