"""How ``fretc audit`` shows its verdicts: the terminal summary (rich), the JUnit XML file
(one test case per requirement x log, for CI) and the progress bar.

All output is deterministic: same logs and requirements, same text (no wall-clock times).
Times are printed as seconds since the log's first tick (``12.300 s``) next to the tick
number; the JSON report (:mod:`monitors.report_model`) also has the absolute ns.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

from rich.markup import escape
from typing import Dict, List, Optional

from .report_model import LogAudit, Verdict, exit_code

__all__ = ["print_summary", "junit_xml", "AuditProgress", "short_log_name"]

_STYLE = {"satisfied": "green", "vacuous": "yellow", "violated": "bold red", "error": "magenta"}


def short_log_name(path: str) -> str:
    """The path relative to the working directory when it lies below it (a URL as is)."""
    if "://" in path:
        return path
    try:
        rel = os.path.relpath(path)
    except ValueError:  # pragma: no cover - other drive on Windows
        return path
    return path if rel.startswith("..") else rel


def _s(ns: Optional[int], start: Optional[int]) -> str:
    if ns is None or start is None:
        return "-"
    return f"{(ns - start) / 1e9:.3f} s"


def _value(v) -> str:
    if isinstance(v, bool):
        return "T" if v else "F"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def print_summary(console, logs: List[LogAudit], plan=None, details: bool = True) -> None:
    """Print the verdict table, per-log notes and, with ``details``, the evidence of each
    violation (trigger, scope interval, obligation, values around it) to a rich Console."""
    from rich.table import Table
    from rich.text import Text

    if plan is not None:
        b = plan.bindings
        clock = "no bindings (CSV columns are the variables)"
        if b is not None:
            tick = (f"tick every {b.tick.period_ns / 1e6:g} ms" if b.tick.period_ns
                    else f"one tick per {b.tick.topic} message")
            clock = f"bindings {', '.join(plan.binding_files) or '--bind'} ({tick}, " \
                    f"{b.time_base} time)"
        console.print(f"fretc audit: {len(plan.requirements)} requirements, {len(logs)} "
                      f"logs; {clock}", markup=False)
        if plan.freeform:
            console.print(f"free-form, not audited: {', '.join(plan.freeform)}", markup=False)
    table = Table(show_lines=False, header_style="bold")
    for col in ("log", "req", "verdict", "first violation", "trigger", "LTL3", "ticks",
                "notes"):
        table.add_column(col, no_wrap=col in ("log", "req", "verdict"))
    for la in logs:
        name = short_log_name(la.log)
        st = la.start_time_ns
        for v in la.verdicts:
            fv = v.first_violation
            first = trig = "-"
            if fv is not None:
                first = f"{_s(fv.at.time_ns, st)} (#{fv.at.tick})"
                if fv.trigger is not None:
                    trig = f"{_s(fv.trigger.time_ns, st)} (#{fv.trigger.tick})"
            ltl3 = v.ltl3.status
            if v.ltl3.tick is not None:
                ltl3 += f" @ {_s(v.ltl3.time_ns, st)}"
            notes = []
            if v.partial:
                where = (_s(la.damage_time_ns, st) if la.damage_time_ns is not None
                         else "the first message")
                notes.append(f"partial (damage at {where})")
            if v.error:
                notes.append(v.error)
            elif v.verdict == "vacuous":
                notes.extend(n for n in v.notes if n.startswith("vacuous"))
            label = v.verdict.upper() if v.verdict == "violated" else v.verdict
            table.add_row(Text(name), Text(v.requirement), Text(label, style=_STYLE[v.verdict]),
                          first, trig, ltl3, str(v.ticks_evaluated), Text("; ".join(notes)))
    console.print(table)
    for la in logs:
        lines = _log_notes(la)
        if lines:
            console.print(f"[bold]{escape(short_log_name(la.log))}[/bold]: " + "; ".join(lines),
                          highlight=False)
    if details:
        for la in logs:
            for v in la.verdicts:
                if v.verdict == "violated":
                    _print_violation(console, la, v)
    counts: Dict[str, int] = {}
    for la in logs:
        for v in la.verdicts:
            counts[v.verdict] = counts.get(v.verdict, 0) + 1
    parts = [f"{counts.get(k, 0)} {k}" for k in ("satisfied", "vacuous", "violated", "error")]
    console.print(f"{', '.join(parts)} (exit {exit_code(logs)})", highlight=False)


def _log_notes(la: LogAudit) -> List[str]:
    st = la.start_time_ns
    out = []
    if la.error:
        out.append(f"[magenta]not audited[/magenta]: {escape(la.error)}")
        return out
    if la.partial:
        if la.damage_time_ns is None:
            out.append("[yellow]partial[/yellow]: the log is damaged before its first "
                       "readable message; nothing to audit")
        else:
            out.append(f"[yellow]partial[/yellow]: the log ends early (damage after "
                       f"{_s(la.damage_time_ns, st)}); audited up to there")
    if la.warmup_ticks:
        out.append(f"{la.warmup_ticks} warm-up ticks not evaluated (waiting for "
                   f"{escape(', '.join(la.waiting_for)) or 'the first messages'}; first evaluated tick "
                   f"at {_s(la.first_time_ns, st)})")
    if la.missing_topics:
        out.append(f"never published: {escape(', '.join(la.missing_topics))}")
    if la.problem_counts:
        out.append("data problems: " + escape(", ".join(f"{k} x{n}"
                                                        for k, n in la.problem_counts.items())))
    return out


def _print_violation(console, la: LogAudit, v: Verdict) -> None:
    from rich.table import Table

    st = la.start_time_ns
    fv = v.first_violation
    console.print(f"\n[bold red]{escape(v.requirement)} violated[/bold red] on "
                  f"{escape(short_log_name(la.log))}: {escape(v.text)}", highlight=False)
    if fv is None:
        return
    if fv.trigger is not None:
        sc = fv.scope
        console.print(f"  trigger at tick {fv.trigger.tick} ({_s(fv.trigger.time_ns, st)}) in the "
                      f"scope interval [{sc[0].tick}, {sc[1].tick}] "
                      f"({_s(sc[0].time_ns, st)} .. {_s(sc[1].time_ns, st)})", markup=False,
                      highlight=False)
    if fv.obligation:
        console.print(f"  obligation: {fv.obligation}", markup=False, highlight=False)
    console.print(f"  {fv.reason}; missed at tick {fv.at.tick} ({_s(fv.at.time_ns, st)}, "
                  f"log time {fv.at.time_ns} ns)", markup=False, highlight=False)
    if v.triggers is not None and v.violations:
        console.print(f"  {v.violations} of {v.triggers} triggers failed", markup=False,
                      highlight=False)
    if not v.values:
        return
    t = Table(show_header=True, header_style="bold", box=None, pad_edge=False)
    t.add_column("tick", justify="right")
    t.add_column("time", justify="right")
    names = list(v.values)
    for n in names:
        t.add_column(n, justify="right")
    topics = list(v.sources)
    for tp in topics:
        t.add_column(f"{tp} @", justify="right")
    rows = list(zip(*[v.values[n] for n in names])) if names else []
    marks = {fv.at.tick: "<- missed"}
    if fv.trigger is not None:
        marks.setdefault(fv.trigger.tick, "<- trigger")
        if fv.trigger.tick == fv.at.tick:
            marks[fv.at.tick] = "<- trigger, missed"
    t.add_column("")
    for k, row in enumerate(rows):
        tick, ns = row[0][0], row[0][1]
        cells = [str(tick), _s(ns, st)] + [_value(c[2]) for c in row]
        for tp in topics:
            lt = v.sources[tp][k][2]
            cells.append(_s(lt, st))
        cells.append(marks.get(tick, ""))
        t.add_row(*cells)
    console.print(t)


def junit_xml(logs: List[LogAudit]) -> str:
    """JUnit XML: a ``testsuite`` per log, a ``testcase`` per requirement (``failure`` when
    violated, ``error`` when not audited; vacuous passes say so in ``system-out``)."""
    root = ET.Element("testsuites", name="fretc audit")
    tot = {"tests": 0, "failures": 0, "errors": 0}
    for la in logs:
        suite = ET.SubElement(root, "testsuite", name=short_log_name(la.log))
        props = ET.SubElement(suite, "properties")
        for k, val in (("partial", str(la.partial).lower()),
                       ("ticks_evaluated", str(la.ticks_evaluated)),
                       ("warmup_ticks", str(la.warmup_ticks))):
            ET.SubElement(props, "property", name=k, value=val)
        counts = {"tests": 0, "failures": 0, "errors": 0}
        st = la.start_time_ns
        cls = "fretc.audit." + os.path.splitext(os.path.basename(la.log.rstrip("/")))[0]
        for v in la.verdicts:
            counts["tests"] += 1
            case = ET.SubElement(suite, "testcase", classname=cls, name=v.requirement, time="0")
            out = [v.text]
            if v.verdict == "violated":
                counts["failures"] += 1
                fv = v.first_violation
                msg = f"{v.requirement} violated"
                body = []
                if fv is not None:
                    msg += f" at {_s(fv.at.time_ns, st)} (tick {fv.at.tick})"
                    if fv.trigger is not None:
                        msg += f"; trigger at {_s(fv.trigger.time_ns, st)} (tick {fv.trigger.tick})"
                    body = [fv.obligation, fv.reason]
                if v.partial:
                    msg += " [partial log]"
                ET.SubElement(case, "failure", message=msg, type="violated").text = \
                    "\n".join(x for x in [v.text] + body if x)
            elif v.verdict == "error":
                counts["errors"] += 1
                ET.SubElement(case, "error", message=v.error or "error", type="error").text = \
                    v.error or ""
            else:
                out.append(f"verdict: {v.verdict}" + (" (partial log)" if v.partial else ""))
                out.extend(n for n in v.notes if n.startswith("vacuous"))
            ET.SubElement(case, "system-out").text = "\n".join(out)
        for k, n in counts.items():
            suite.set(k, str(n))
            tot[k] += n
        suite.set("skipped", "0")
        suite.set("time", "0")
    for k, n in tot.items():
        root.set(k, str(n))
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


class AuditProgress:
    """A rich progress display: one bar for the logs done, one per log being read (fraction
    of its log time). Used as the ``progress`` object of :func:`monitors.audit.audit_logs`."""

    def __init__(self, console, total: int):
        from rich.progress import (BarColumn, Progress, TaskProgressColumn, TextColumn,
                                   TimeElapsedColumn)

        self.progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                 TaskProgressColumn(), TimeElapsedColumn(), console=console,
                                 transient=True)
        self.total = self.progress.add_task("logs", total=total)
        self.tasks: Dict[int, int] = {}

    def __enter__(self):
        self.progress.start()
        return self

    def __exit__(self, *exc):
        self.progress.stop()

    def start(self, index: int, path: str) -> None:
        self.tasks[index] = self.progress.add_task(short_log_name(path), total=1.0)

    def update(self, index: int, fraction: float) -> None:
        task = self.tasks.get(index)
        if task is not None:
            self.progress.update(task, completed=fraction)

    def done(self, index: int, la) -> None:
        task = self.tasks.pop(index, None)
        if task is not None:
            self.progress.remove_task(task)
        self.progress.advance(self.total)
