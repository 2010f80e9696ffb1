"""Fleet statistics: per requirement, how the runs of an audit of several logs came out, and
for a requirement ``with probability OP p`` the estimate of the probability FRET bounds,
its exact interval and the statistical verdict (docs/guide/statistics.md).

Design notes: ARCHITECTURE.md, `audit/fleet/statistics.py`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TYPE_CHECKING

from fretc.audit.fleet.intervals import (MAX_MORE_RUNS, Counts, check_confidence, clopper_pearson,
                                         cluster_interval, decide, more_runs)

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit
    from fretc.audit.model import AuditPlan

__all__ = ["RequirementStatistics", "fleet_statistics", "plan_statistics", "clopper_pearson",
           "decide", "more_runs", "judge_counts", "UNKNOWN_POLICIES",
           "STAT_VERDICTS", "TRIAL_UNITS", "MAX_MORE_RUNS", "unknown_policy"]

UNKNOWN_POLICIES = ("worst-case", "exclude")
STAT_VERDICTS = ("holds", "fails", "undecided")
TRIAL_UNITS = ("trigger", "run")


def unknown_policy(name: str) -> str:
    """The unknown-outcome policy named ``name`` (``fail``: the name ``worst-case`` had
    before); ``ValueError`` for another."""
    name = "worst-case" if name == "fail" else name
    if name not in UNKNOWN_POLICIES:
        raise ValueError(f"unknown-run policy {name!r}: one of {', '.join(UNKNOWN_POLICIES)}")
    return name


@dataclass
class RequirementStatistics:
    """One requirement over the runs of an audit (module docstring).

    Attributes:
        id: the requirement's id; ``trial``: ``trigger`` or ``run``.
        runs: logs audited for it; ``satisfied``, ``vacuous``, ``violated``, ``unknown``,
            ``error``: the runs of each verdict (they add up to ``runs``).
        successes, trials: the trials of known outcome used, and the satisfied ones;
            ``unknown_trials``: trials of unknown outcome (``worst-case``: spanned by the
            interval; ``exclude``: 0); ``effective_trials``: the interval's sample size.
        triggers: per trigger, the triggers of all runs (``satisfied``, ``violated``,
            ``cut``, ``unknown``) and ``hidden_runs`` (runs where one may have fired in
            unknown ticks); ``triggers_per_run``: ``min``, ``mean``, ``max`` of the
            triggers of each run counted; None per run.
        estimate: ``successes / trials`` (None without trials); ``interval``: ``[lo, hi]``
            at ``confidence``.
        unknown_policy: ``worst-case`` or ``exclude``.
        bound: ``{"op", "p"}`` of a probability requirement, else None; ``verdict``:
            ``holds`` / ``fails`` / ``undecided`` for those (None otherwise);
            ``more_runs``: for ``undecided``, further runs that would decide it at the
            observed rate; ``why``: a sentence for ``undecided``.
    """

    id: str
    runs: int = 0
    satisfied: int = 0
    vacuous: int = 0
    violated: int = 0
    unknown: int = 0
    error: int = 0
    successes: int = 0
    trials: int = 0
    estimate: float | None = None
    interval: tuple[float, float] = (0.0, 1.0)
    confidence: float = 0.95
    unknown_policy: str = "worst-case"
    bound: dict[str, Any] | None = None
    verdict: str | None = None
    more_runs: int | None = None
    why: str | None = None
    trial: str = "run"
    unknown_trials: int = 0
    effective_trials: float = 0.0
    triggers: dict[str, int] | None = None
    triggers_per_run: dict[str, float] | None = None
    counts: Counts | None = None  # the clustered counts behind the interval (not in JSON)
    blocked: str | None = None    # why no bound can be decided (not in JSON: see why)

    def to_json(self) -> dict:
        """The object of the audit JSON's ``statistics`` list (docs/reference/audit-json.md):
        every attribute but ``counts`` and ``blocked``, ``interval`` as ``[lo, hi]``."""
        return {"id": self.id, "trial": self.trial, "runs": self.runs,
                "satisfied": self.satisfied, "vacuous": self.vacuous,
                "violated": self.violated, "unknown": self.unknown, "error": self.error,
                "successes": self.successes, "trials": self.trials,
                "unknown_trials": self.unknown_trials,
                "effective_trials": self.effective_trials,
                "triggers": self.triggers, "triggers_per_run": self.triggers_per_run,
                "estimate": self.estimate, "interval": [self.interval[0], self.interval[1]],
                "confidence": self.confidence, "unknown_policy": self.unknown_policy,
                "bound": self.bound, "verdict": self.verdict, "more_runs": self.more_runs,
                "why": self.why}


def judge_counts(st: RequirementStatistics, op: str | None, p: float | None) -> None:
    """Fill ``st``'s estimate, interval and (with a bound ``op p``) verdict from its
    clustered counts ``st.counts`` (made from ``successes`` of ``trials``, one a run, when
    None); shared by the fleet audit and ``fretc estimate``."""
    c = st.counts
    if c is None:  # one trial a run
        m = st.trials + st.unknown_trials
        c = st.counts = Counts(st.successes, st.trials, st.unknown_trials, m, m, m)
    st.successes, st.trials, st.unknown_trials = c.successes, c.trials, c.unknown
    st.effective_trials = c.effective
    st.estimate = c.estimate
    st.interval = cluster_interval(c, st.confidence)
    if op is None:
        return
    st.bound = {"op": op, "p": p}
    assert p is not None  # (an operator comes with its bound)
    st.verdict = decide(op, p, *st.interval)
    if st.blocked is not None:
        st.verdict, st.why = "undecided", st.blocked
    elif c.trials == 0:  # nothing judged: even a bound every p meets (<= 1) was not checked
        st.verdict = "undecided"
        _why_undecided(st, op, p, c)
    elif st.trial == "trigger" and c.runs == 1:
        st.verdict = "undecided"
        st.why = (f"one run ({c.size} trigger{'s' if c.size != 1 else ''}): the triggers "
                  "of one run are not independent trials and decide no bound; audit "
                  "several runs")
    elif st.verdict == "undecided":
        _why_undecided(st, op, p, c)


def _why_undecided(st: RequirementStatistics, op: str, p: float, c: Counts) -> None:
    """``st.more_runs`` and ``st.why`` of an undecided bound."""
    unit = "triggers" if st.trial == "trigger" else "runs"
    if c.size == 0:
        st.why = f"no trial: no {unit[:-1]} was judged, no estimate"
        return
    if c.trials == 0:
        st.why = (f"no trial of known outcome: the {c.unknown} {unit} of unknown outcome "
                  "(unknown or error) could each have gone either way")
        return
    st.more_runs = more_runs(op, p, c, st.confidence)
    pct = f"{100 * st.confidence:g} %"
    unknown = (f" ({c.unknown} of unknown outcome, counted either way)" if c.unknown else "")
    seen = f"{c.trials + c.unknown} {unit}{unknown}"
    if st.trial == "trigger":
        seen += f" of {c.runs} runs"
    if op == "=":
        st.why = (f"{p:g} is inside the {pct} interval; no finite number of trials confirms "
                  "an equality (write >= or <=)")
    elif st.more_runs is None:
        st.why = (f"the observed rate {c.successes}/{c.trials} is the bound itself (or too "
                  f"close to it): no number of runs at this rate decides it ({seen})")
    else:
        st.why = (f"{p:g} is inside the {pct} interval after {seen}; about "
                  f"{st.more_runs} more runs at the observed rate {c.successes}/{c.trials} "
                  "would decide it")


def fleet_statistics(logs: list, bounds: dict[str, Any], confidence: float = 0.95,
                     unknown: str = "worst-case",
                     trial: str = "trigger") -> list[RequirementStatistics]:
    """Per requirement (in ``bounds``' order: id -> :class:`fretc.compiler.ir.ProbabilityBound`
    or None), its :class:`RequirementStatistics` over ``logs``
    (:class:`fretc.audit.verdict.LogAudit` list: one run each; module docstring). Raises
    ``ValueError`` for an unknown policy or unit, or a confidence outside (0, 1)."""
    policy = unknown_policy(unknown)
    if trial not in TRIAL_UNITS:
        raise ValueError(f"trial {trial!r}: one of {', '.join(TRIAL_UNITS)}")
    confidence = check_confidence(confidence)
    out = []
    for rid, bound in bounds.items():
        st = RequirementStatistics(rid, confidence=confidence, unknown_policy=policy,
                                   trial=trial if bound is not None else "run")
        verdicts = [_verdict_of(la, rid) for la in logs]
        for v in verdicts:
            kind = "error" if v is None else v.verdict
            setattr(st, kind, getattr(st, kind) + 1)
            st.runs += 1
        if st.trial == "trigger":
            _count_triggers(st, verdicts, policy)
        else:
            _count_runs(st, policy)
        judge_counts(st, None if bound is None else bound.op,
                     None if bound is None else bound.p)
        out.append(st)
    return out


def _verdict_of(la, rid: str):
    """The verdict of ``rid`` on the log ``la``; None when it was not judged (a log error
    or an error verdict)."""
    if la.error:
        return None
    v = next((v for v in la.verdicts if v.requirement == rid), None)
    return None if v is None or v.verdict == "error" else v


def _count_runs(st: RequirementStatistics, policy: str) -> None:
    """One trial per run: satisfied or vacuous runs succeed, violated ones fail; unknown and
    error runs are of unknown outcome (``worst-case``) or left out."""
    c = st.counts = Counts()
    for _ in range(st.satisfied + st.vacuous):
        c.add(1, 1)
    for _ in range(st.violated):
        c.add(0, 1)
    if policy == "worst-case":
        for _ in range(st.unknown + st.error):
            c.add(0, 0, 1)


def _count_triggers(st: RequirementStatistics, verdicts: list, policy: str) -> None:
    """The trials of each run's triggers (:mod:`fretc.audit.trials`), runs as clusters."""
    c = st.counts = Counts()
    tot = {"satisfied": 0, "violated": 0, "cut": 0, "unknown": 0, "hidden_runs": 0}
    sizes: list[int] = []
    blind = 0
    for v in verdicts:
        t = None if v is None else v.trials
        if t is None:
            blind += 1
            continue
        for key in ("satisfied", "violated", "cut", "unknown"):
            tot[key] += getattr(t, key)
        tot["hidden_runs"] += bool(t.hidden)
        sizes.append(t.trials + t.unknown)
        c.add(t.satisfied, t.trials, t.unknown if policy == "worst-case" else 0)
    st.triggers = tot
    if sizes:
        st.triggers_per_run = {"min": min(sizes), "mean": sum(sizes) / len(sizes),
                               "max": max(sizes)}
    if blind and policy == "worst-case":
        st.blocked = (f"{blind} run{'s' if blind != 1 else ''} could not be judged per "
                      "trigger (an error, or its triggers could not be counted): any number "
                      "of triggers, of any outcome, may be hidden there; fix them, or leave "
                      "them out with --unknown-runs exclude")


def plan_statistics(plan: AuditPlan, logs: list[LogAudit], confidence: float = 0.95, unknown: str = "worst-case",
                    trial: str = "trigger") -> list[RequirementStatistics] | None:
    """The fleet statistics of an audit plan's requirements
    (:class:`fretc.audit.model.AuditPlan`) over ``logs``, or None when the audit is of one
    log and no requirement has a probability bound (the audit JSON then has no
    ``statistics``)."""
    bounds = {r.id: getattr(r.compiled, "probability", None) for r in plan.requirements}
    if len(logs) <= 1 and not any(bounds.values()):
        return None
    return fleet_statistics(logs, bounds, confidence, unknown, trial)
