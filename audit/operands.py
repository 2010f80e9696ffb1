"""The numbers behind a violated requirement's boolean variables: the operands of the
comparisons its bindings are made of, read in a second pass over the log."""

from __future__ import annotations

from typing import TYPE_CHECKING

from fretc.signals.bindings import Bindings, operand_signals
from fretc.monitors.stepwise import to_python
from fretc.common.problems import LogError, SignalError
from fretc.signals import sample_blocks
from fretc.logs import open_log
from fretc.logs.allowance import with_allowance
from fretc.audit.model import AuditPlan
from fretc.audit.passes import ClockKey, clock_key

if TYPE_CHECKING:
    from fretc.audit.model import RequirementPlan
    from fretc.audit.columns import ClockPass
    from fretc.audit.verdict import Verdict
    from fretc.logs.base import LogSource

__all__ = ["operand_values"]


def operand_values(path: str, plan: AuditPlan, bindings: Bindings,
                   active: list[RequirementPlan], verdicts: dict[int, Verdict],
                   passes: dict[int, ClockPass], first: LogSource | None = None) -> None:
    """Evidence of violations: the numbers behind their boolean variables (the operands of
    the comparisons a binding is made of, :func:`fretc.signals.bindings.operand_signals`) at the
    ticks whose values are shown. A second streaming pass over the log, only when something
    was violated, only for those operands, each on its requirement's own clock (so tick
    indexes match the first pass), and only up to the last tick shown.

    Args:
        active: the requirements judged; ``verdicts``: requirement index -> Verdict;
            ``passes``: requirement index -> its :class:`fretc.audit.columns.ClockPass`;
            ``first``: the first pass's source (its ``reopen()`` spares a second read of a
            flight log), or None.
    """
    wanted, groups, needs = _operands_wanted(bindings, active, verdicts)
    if not wanted:
        return
    at = {(key, t) for key, _a, _v, ticks in needs for t in ticks}
    last: dict[ClockKey, int] = {}  # clock -> its last tick shown: the pass ends after it
    for key, t in at:
        last[key] = max(last.get(key, -1), t)
    aux_bindings = Bindings({name: aux for name, (_l, aux) in wanted.items()}, bindings.tick,
                            bindings.time_base, bindings.header_lag_ns, bindings.source)
    got: dict[tuple[ClockKey, str], dict[int, object]] = {}
    try:
        source = (first.reopen() if first is not None else None) or with_allowance(open_log(
            path, csv_period_ns=plan.csv_period_ns, msg_path=plan.config.msg_path),
            plan.bindings.allowance if plan.bindings is not None else None)
        done: set[ClockKey] = set()
        blocks = iter(sample_blocks(source, aux_bindings, groups,
                                    _last_time(needs, passes, verdicts)))
        for key, blk in blocks:
            for i in range(len(blk.times)):
                if (key, blk.start + i) not in at:
                    continue
                for name in groups[key][0]:
                    if name in blk.values:
                        got.setdefault((key, name), {})[blk.start + i] = \
                            to_python(blk.values[name][i])
            if blk.start + len(blk.times) > last.get(key, -1):
                done.add(key)
            if len(done) >= len(last):  # every tick shown is read: the rest of the log is not
                break
        close = getattr(blocks, "close", None)
        if close is not None:  # the reader's file closed now, not when collected
            close()
    except (LogError, SignalError, OSError):
        return  # the first pass already reported what is wrong with the log
    for key, aux_name, v, ticks in needs:
        label = wanted[aux_name][0]
        times = None
        for r_index, res in passes.items():
            if verdicts[r_index] is v:
                times = res.times
        vals = got.get((key, aux_name), {})
        assert times is not None  # (v is the verdict of one of the passes)
        rows = [(t, int(times[t]), vals[t]) for t in ticks if t in vals]
        if rows:
            v.values[label] = rows


def _last_time(needs: list, passes: dict[int, ClockPass], verdicts: dict[int, Verdict]
               ) -> int | None:
    """The time (ns, the clock's time base) of the last tick whose operands are shown, over
    every requirement of ``needs`` ((clock, operand, verdict, ticks)): the read of the
    operands ends at the first message after it; None when a tick shown has no time."""
    out = None
    for _key, _aux, v, ticks in needs:
        times = next((res.times for i, res in passes.items() if verdicts[i] is v), None)
        if times is None or not ticks or max(ticks) >= len(times):
            return None
        t = int(times[max(ticks)])
        out = t if out is None else max(out, t)
    return out


def _operands_wanted(bindings: Bindings, active, verdicts):
    """(operand signal name -> (label, its binding); clock -> (signal names, clock); one
    (clock, signal name, verdict, ticks shown) per operand of a shown variable)."""
    wanted: dict[str, tuple[str, object]] = {}  # aux name -> (label, binding)
    groups: dict[ClockKey, tuple[list[str], frozenset]] = {}
    needs: list[tuple[ClockKey, str, object, list[int]]] = []
    for r in active:
        v = verdicts[r.index]
        if v.verdict != "violated" or not v.values:
            continue
        key = clock_key(r, bindings)
        for name in r.variables:
            b = bindings.variables.get(name)
            if b is None or name not in v.values:
                continue
            try:
                pairs = operand_signals(b)
            except Exception:  # an operand that cannot stand alone: show the boolean only
                continue
            for label, aux in pairs:
                wanted[aux.name] = (label, aux)
                names = groups.setdefault(key, ([], key.topics))[0]
                if aux.name not in names:
                    names.append(aux.name)
                needs.append((key, aux.name, v, [t for t, _ns, _x in v.values[name]]))
    return wanted, groups, needs
