"""How ``fretc audit`` shows its verdicts: the terminal summary (rich) and the damage of a
partial log in one sentence (the progress bar: :mod:`fretc.reports.progress`; the JUnit XML
file: :mod:`fretc.reports.junit`).

All output is deterministic: same logs and requirements, same text (no wall-clock times).
Times are printed as seconds since the log's first tick (``12.300 s``) next to the tick
number; the JSON report (:mod:`fretc.audit.verdict`) also has the absolute ns.
"""

from __future__ import annotations

import math
import os
from collections import Counter
from functools import lru_cache
from typing import Any, TYPE_CHECKING, cast
from rich.cells import cell_len
from rich.markup import escape as _markup_escape
from rich.table import Table
from rich.text import Text

from fretc.common.textsafe import terminal_text
from fretc.common.problems import RECORDED_GAPS
from fretc.common.units import format_offset
from fretc.logs.allowance import allowance_text
from fretc.logs.recorded_gaps import LEFT_FOR_GOOD, RUN_END

from fretc.audit.verdict import LogAudit, Verdict, exit_code, incomplete
from fretc.reports.verdicts import format_value

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan
    from rich.console import Console

__all__ = ["print_summary", "short_log_name", "damage_summary", "escape"]

_STYLE = {"satisfied": "green", "vacuous": "yellow", "violated": "bold red",
          "unknown": "yellow", "error": "magenta"}


def escape(text: object) -> str:
    """Text from the inputs for rich markup: newlines, control and bidi characters shown
    escaped (:func:`fretc.common.textsafe.terminal_text`: a newline in a topic, a frame id or a
    joint name cannot start a line of its own), then markup escaped."""
    return _markup_escape(terminal_text(text, keep=""))


def _T(text, keep: str = "") -> Text:
    """``text`` as one line (``keep="\n"``: our own multi-line diagnostics, whose parts
    from the inputs are escaped where they are written)."""
    return Text(terminal_text(text, keep=keep))


def short_log_name(path: str) -> str:
    """The path relative to the working directory when it lies below it (a URL as is)."""
    return path if "://" in path else _short_log_name(path, os.getcwd())


@lru_cache(maxsize=4096)
def _short_log_name(path: str, cwd: str) -> str:
    """:func:`short_log_name` of ``path`` from ``cwd`` (kept: a summary names a log once per
    verdict, and ``os.path.relpath`` costs about 10 µs)."""
    try:
        rel = os.path.relpath(path, cwd)
    except ValueError:  # pragma: no cover - other drive on Windows
        return path
    return path if rel.startswith("..") else rel


def _value(v) -> str:
    return format_value(v)  # every digit it needs: which side of a threshold it is on


#: The matrix (logs x requirements) is used while its smaller side has at most this many
#: entries; beyond, a list of the verdicts that are not plain passes.
MATRIX_MAX = 10
#: ... and its larger side at most this many (a per-entity requirement over 100,000 entities
#: would print a row per instance: the list of the verdicts that are not plain passes instead;
#: the JSON, JUnit and report keep every verdict).
MATRIX_ROWS_MAX = 1000


def robustness_text(value: float | str | None, none: str = "") -> str:
    """A robustness as fretc shows it (terminal, report, falsify): signed, 4 significant
    digits, ``+inf`` / ``-inf`` when a boolean decides it; ``none`` when there is none.
    ``value`` may also be the audit JSON's text of an infinity (``"inf"``, ``"-inf"``)."""
    if value is None:
        return none
    value = float(value) + 0.0  # a zero is +0, whichever sign it was computed with
    if math.isinf(value):
        return "+inf" if value > 0 else "-inf"
    return f"{value:+.4g}"


def _cell(v: Verdict, st: int | None) -> str:
    r = v.robustness
    rob = f"\n({robustness_text(r)})" if r is not None and math.isfinite(r) else ""
    if v.verdict == "violated":
        fv = v.first_violation
        at = f" {format_offset(fv.at.time_ns, st)}" if fv is not None else ""
        return f"VIOLATED{at}" + (" *" if v.partial else "") + rob
    return v.verdict + (" *" if v.partial else "") + rob


def print_summary(console: Console, logs: list[LogAudit], plan: AuditPlan | None = None,
                  details: bool = True,
                  verbose: bool = False, allow_partial: bool = False,
                  input_errors: bool = False, statistics: list | None = None,
                  command: str = "fretc audit") -> None:
    """Print the verdicts to a rich Console: a header line, the verdict matrix (logs x
    requirements; cells give the first violation's time in seconds from the log's start),
    per-log notes, errors in full below the table (never cut inside a cell), with
    ``details`` one evidence block per violation (trigger, obligation, the missed tick with
    its tick time and the log time of the message that decided it) and, with ``verbose``,
    the values around each violation; last the counts and the exit code (with
    ``statistics``, :mod:`fretc.audit.fleet.statistics`: the fleet table first when a requirement has
    a probability bound or with ``verbose``, and probability requirements judged by their
    statistical verdict). ``command`` heads the output (``fretc watch``: one run, no log
    count)."""
    if plan is not None:
        _print_plan(console, plan, len(logs) if command == "fretc audit" else None, command)
    reqs = _requirement_names(logs, MATRIX_ROWS_MAX)
    if reqs is not None and min(len(logs), len(reqs)) <= MATRIX_MAX and \
            len(logs) <= MATRIX_ROWS_MAX and logs:
        _print_matrix(console, logs, reqs)
    else:
        _print_incomplete(console, logs)
    if any(v.robustness is not None for la in logs for v in la.verdicts):
        console.print("(n): robustness, the margin to the threshold in the variable's unit, "
                      "negative exactly when violated; none shown: decided by booleans "
                      "(+-inf) or no robustness", highlight=False)
    if any(v.partial for la in logs for v in la.verdicts):
        console.print("* partial log: judged on the messages read (gaps: unknown ticks; a cut: "
                      "nothing after it)", highlight=False)
    for la in logs:
        lines = _log_notes(la, verbose)
        if lines:
            console.print(f"[bold]{escape(short_log_name(la.log))}[/bold]: " + "; ".join(lines),
                          highlight=False)
    _print_errors(console, logs)
    if details:
        ids = tool_ids(plan)
        bad = [(la, v) for la in logs for v in la.verdicts if v.verdict == "violated"]
        if verbose:
            for la, v in bad:
                _print_violation_verbose(console, la, v, ids.get(v.requirement))
        elif bad:  # (in one call: a call of rich's print costs about a millisecond)
            text = Text()
            for k, (la, v) in enumerate(bad):
                if k:
                    text.append("\n")
                _violation_text(la, v, ids.get(v.requirement), into=text)
            # lines that all fit are printed as they are: rich's word wrap would leave them
            # so, at 0.1 ms a line (0.3 s for 1,001 violations)
            width = console.width
            fits = all(cell_len(line) <= width for line in text.plain.split("\n"))
            console.print(text, highlight=False, soft_wrap=fits)
    if statistics is not None and (verbose or any(st.bound is not None for st in statistics)):
        # (plain requirements' fleet statistics: in the JSON, and here with --verbose)
        from fretc.reports.statistics import print_statistics

        print_statistics(console, statistics)
    _print_counts(console, logs, input_errors, allow_partial, statistics)


def _requirement_names(logs: list[LogAudit], most: int) -> list[str] | None:
    """The verdicts' requirement names in order of first appearance; None as soon as there
    are more than ``most`` (100,000 entities: the matrix is not printed, nor are they all
    gathered)."""
    names: dict[str, None] = {}
    for la in logs:
        for v in la.verdicts:
            names[v.requirement] = None
            if len(names) > most:
                return None
    return list(names)


def _plural(n: int, word: str) -> str:
    """``1 log``, ``2 logs``."""
    return f"{n} {word}{'' if n == 1 else 's'}"


def _print_plan(console, plan, n_logs: int | None, command: str = "fretc audit") -> None:
    """The header: the command, requirements, logs (``n_logs`` None: a watch, one run) and
    the clock of the bindings."""
    b = plan.bindings
    clock = "no bindings (CSV columns are the variables)"
    if getattr(plan, "variants", None):
        clock = "bindings per log: " + "; ".join(
            f"{f} ({sel.text()})" for sel, f, _sub in plan.variants)
    elif b is not None:
        tick = (f"tick every {b.tick.period_ns / 1e6:g} ms" if b.tick.period_ns
                else f"one tick per {b.tick.topic} message")
        if b.tick.nan == "false":
            tick += ", NaN compares false"
        if b.tick.inf == "value":
            tick += ", ±inf read as numbers"
        clock = f"bindings {', '.join(plan.binding_files) or '--bind'} ({tick}, " \
                f"{b.time_base} time)"
        if b.allowance:  # (a reaction allowance: the verdicts are read with it)
            clock += f"; allowance: {allowance_text(b.allowance)}"
    what = _plural(len(plan.requirements), "requirement")
    what += "" if n_logs is None else f", {_plural(n_logs, 'log')}"
    console.print(f"{command}: {what}; {clock}", markup=False)
    if plan.freeform:
        console.print(f"free-form, not audited: {', '.join(plan.freeform)}", markup=False)
    for line in tool_lines(plan):
        console.print(line, markup=False, highlight=False)


def tool_ids(plan: AuditPlan | None) -> dict[str, str]:
    """Requirement id -> the identifier of the tool it was read from (ReqIF SPEC-OBJECT,
    Doorstop UID, FRET reqid), for the requirements that have one (none without a plan)."""
    out = {}
    for r in getattr(plan, "requirements", None) or []:
        origin = getattr(getattr(r.compiled, "entry", None), "origin", None)
        if origin is not None:
            out[r.id] = origin.tool_id
    return out


def tool_lines(plan: AuditPlan | None) -> list[str]:
    """The header lines of requirements read from tools: each id with its tool id (one line
    per source file), then the items listed as not formalized (no FRETish text)."""
    by_file: dict[str, list[str]] = {}
    for r in getattr(plan, "requirements", None) or []:
        origin = getattr(getattr(r.compiled, "entry", None), "origin", None)
        if origin is not None and origin.format != "fret":
            where = (f"document {origin.container} ({os.path.dirname(origin.file)})"
                     if origin.format == "doorstop" else origin.file)
            by_file.setdefault(f"{origin.format} {where}", []).append(
                r.id if r.id == origin.tool_id else f"{r.id} = {origin.tool_id}")
    lines = [f"from {k}: {', '.join(v)}" for k, v in by_file.items()]
    missing = [e.id if e.origin is None or e.id == e.origin.tool_id
               else f"{e.id} = {e.origin.tool_id}"
               for e in getattr(plan, "not_formalized", None) or []]
    if missing:
        lines.append(f"not formalized (no FRETish text), not audited: {', '.join(missing)}")
    return lines


def _print_matrix(console, logs: list[LogAudit], reqs: list[str]) -> None:
    """The verdict matrix: a row per log and a column per requirement when there are no
    more requirements than logs (or more than :data:`MATRIX_MAX` logs), else the other way
    round."""
    cells: dict[tuple, Verdict] = {(la.log, v.requirement): v for la in logs for v in la.verdicts}
    starts = {la.log: la.start_time_ns for la in logs}
    by_log = len(reqs) <= len(logs) or len(logs) > MATRIX_MAX
    # logs (LogAudit) and requirement ids (str), or the other way round
    rows, cols = cast("tuple[list[Any], list[Any]]", (logs, reqs) if by_log else (reqs, logs))
    table = Table(show_lines=False, header_style="bold")
    table.add_column("log" if by_log else "req", no_wrap=True)
    for c in cols:
        table.add_column(terminal_text(c) if by_log else terminal_text(short_log_name(c.log)),
                         no_wrap=True)
    for row in rows:
        out = [_T(short_log_name(row.log) if by_log else row)]
        for c in cols:
            la_log, req = (row.log, c) if by_log else (c.log, row)
            v = cells.get((la_log, req))
            if v is None:
                out.append(Text("-"))
            else:
                out.append(Text(_cell(v, starts[la_log]), style=_STYLE.get(v.verdict, "")))
        table.add_row(*out)
    console.print(table)


def _print_incomplete(console, logs: list[LogAudit]) -> None:
    """Instead of a matrix too large to read: the verdicts that are not complete passes, a
    line each (log, requirement, verdict in aligned columns; a table of rich would take
    half a millisecond a row, and this list is printed when there are thousands)."""
    rows: list[tuple[str, str, str, str]] = []
    for la in logs:
        name = terminal_text(short_log_name(la.log), keep="")
        for v in [v for v in la.verdicts
                  if v.partial or v.verdict not in ("satisfied", "vacuous")]:
            rows.append((name, terminal_text(v.requirement, keep=""),
                         _cell(v, la.start_time_ns).replace("\n", " "),
                         _STYLE.get(v.verdict, "")))
    if rows:
        w_log = max(cell_len("log"), *(cell_len(r[0]) for r in rows)) + 2
        w_req = max(cell_len("req"), *(cell_len(r[1]) for r in rows)) + 2
        out = Text()
        out.append("log".ljust(w_log) + "req".ljust(w_req) + "verdict", style="bold")
        for log, req, cell, style in rows:
            out.append(f"\n{log}{' ' * (w_log - cell_len(log))}{req}"
                       f"{' ' * (w_req - cell_len(req))}")
            out.append(cell, style=style)
        console.print(out, highlight=False, no_wrap=True, overflow="ignore", crop=False)
    total = sum(len(la.verdicts) for la in logs)
    console.print(f"(only verdicts that are not complete passes are listed: {len(rows)} of "
                  f"{total})", highlight=False)


def _print_errors(console, logs: list[LogAudit]) -> None:
    """Errors and unknown verdicts in full, outside the table; one requirement's error once
    for all logs."""
    seen: dict[tuple[str, str], list[str]] = {}
    for la in logs:
        for v in la.verdicts:
            if v.verdict == "error" and v.error and not la.error:
                seen.setdefault(("error", f"{v.requirement}: {v.error}"), []).append(
                    short_log_name(la.log))
            elif v.verdict == "unknown" and v.unknown_reason:
                seen.setdefault(("unknown", f"{v.requirement}: {v.unknown_reason}"), []).append(
                    short_log_name(la.log))
    for (kind, text), where in seen.items():
        on = where[0] if len(where) == 1 else f"{len(where)} logs"
        # an error may be a requirement's diagnostic (its source line and caret under it)
        console.print(Text(f"{kind} ", style=_STYLE[kind])
                      + _T(f"({on}) {text}", keep="\n" if kind == "error" else ""))


def _print_counts(console, logs: list[LogAudit], input_errors: bool,
                  allow_partial: bool, statistics: list | None = None) -> None:
    """The last line: the count of each verdict and the exit code with its meaning."""
    counts = Counter(v.verdict for la in logs for v in la.verdicts)
    parts = [f"{counts.get(k, 0)} {k}" for k in ("satisfied", "vacuous", "violated", "unknown",
                                                 "error")]
    parts += [f"{n} {k}" for k, n in sorted(counts.items())
              if k not in ("satisfied", "vacuous", "violated", "unknown", "error")]
    code = exit_code(logs, input_errors, allow_partial, statistics)
    why = {0: "", 1: ": a requirement is violated" + (
               " or a probability requirement fails"
               if any(st.bound is not None for st in statistics or ()) else ""),
           2: ": something could not be audited",
           3: ": no violation, but a log is partial or had data problems, or a verdict is "
              "unknown", 5: ": a probability requirement is undecided (too few runs)"
           }.get(code, "")
    unchecked = [la for la in logs if la.integrity and not la.error]
    if unchecked:  # (the safety manual's limit: a changed byte reads as data)
        example = unchecked[0]
        console.print(f"integrity not checked in {len(unchecked)} of {len(logs)} log"
                      f"{'s' if len(logs) != 1 else ''} ({short_log_name(example.log)}: "
                      f"{example.integrity})", highlight=False)
    if code == 0 and allow_partial and any(incomplete(la) for la in logs):
        # --allow-partial changes the exit code, never a verdict: say what it let through
        why = (f": --allow-partial; {counts.get('unknown', 0)} unknown verdicts are not "
               "passes, and partial logs were judged only up to their damage")
    console.print(f"{', '.join(parts)} (exit {code}{why})", highlight=False)


def _log_notes(la: LogAudit, verbose: bool = False) -> list[str]:
    st = la.start_time_ns
    out = []
    if la.error:
        out.append(f"[magenta]not audited[/magenta]: {escape(la.error)}")
        return out
    if la.partial:
        out.append("[yellow]partial[/yellow]: " + escape(damage_summary(la)))
    if verbose:
        for v in la.verdicts:
            if v.warmup_ticks:
                out.append(f"{escape(v.requirement)}: {v.warmup_ticks} warm-up ticks (waiting "
                           f"for {escape(', '.join(v.waiting_for)) or 'the first messages'}; "
                           f"first evaluated tick at {format_offset(v.first_tick_ns, st)})")
    for w in la.warnings:
        out.append(f"[yellow]warning[/yellow]: {escape(w)}")
    for v in la.verdicts:  # events a plain binding could not see (docs/bindings.md)
        if not v.missed_changes:  # (no note of one: 100,000 entities' notes unread)
            continue
        for n in v.notes:
            if any(n.startswith(f"{var}: ") for var in v.missed_changes):
                out.append(f"[yellow]between ticks[/yellow] {escape(v.requirement)}: "
                           f"{escape(n)}")
    if la.missing_topics:
        out.append(f"never published: {escape(', '.join(la.missing_topics))}")
    if la.problem_counts:
        out.append("data problems: " + escape(", ".join(f"{k} x{n}"
                                                        for k, n in la.problem_counts.items())))
    # what a live transport said about topics it could not read (a publisher known but
    # silent, an incompatible QoS): said in full, never only counted
    for p in la.problems:
        if p.get("kind") == "protocol" and p.get("detail"):
            out.append(f"transport: {escape(str(p['detail']))}")
    return out


def _headers(names: list[str]) -> list[str]:
    """Short column headers that stay unique: of each name (an operand label ``var: expr``
    counts by its expression) the fewest trailing dotted components that no other name
    ends with (``…linear.y`` for ``/cmd_vel_filtered.linear.y``); plain names as they are."""
    keys = [n.split(": ", 1)[1] if ": " in n else n for n in names]
    out = []
    for i, (n, k) in enumerate(zip(names, keys)):
        if (": " not in n and len(n) <= 20) or len(k) <= 20:
            out.append(k)
            continue
        parts = k.split(".")
        h = k
        for j in range(min(2, len(parts)), len(parts) + 1):
            cand = ".".join(parts[-j:])
            if not any(o != k and (o == cand or o.endswith("." + cand) or o.endswith(cand))
                       for o in keys[:i] + keys[i + 1:]) and cand not in out:
                h = cand if j == len(parts) else "…" + cand
                break
        out.append(h)
    return out


def _violation_text(la: LogAudit, v: Verdict, tool_id: str | None = None,
                    into: Text | None = None) -> Text:
    """Violation ``v``'s heading and evidence lines (trigger, obligation, robustness, the
    missed tick with the log time of the message that decided it), as printed: appended to
    ``into`` when given (one text for many violations), else a new text; returns it."""
    st = la.start_time_ns
    fv = v.first_violation
    clock = "header-stamp clock" if la.time_base == "header" else "log clock"
    named = v.requirement if tool_id in (None, v.requirement) else \
        f"{v.requirement} ({tool_id})"
    head = Text() if into is None else into
    head.append("\n")
    head.append(terminal_text(f"{named} violated", keep=""), style="bold red")
    head.append(terminal_text(f" on {short_log_name(la.log)}: {v.text}", keep=""))
    if fv is None:
        return head
    lines = [""]
    if fv.trigger is not None and fv.scope is not None:  # (a trigger is in its scope interval)
        sc = fv.scope
        lines.append(f"  trigger at tick {fv.trigger.tick} "
                     f"({format_offset(fv.trigger.time_ns, st)}) in the "
                     f"scope interval [{sc[0].tick}, {sc[1].tick}] "
                     f"({format_offset(sc[0].time_ns, st)} .. "
                     f"{format_offset(sc[1].time_ns, st)})"
                     + (f"; obligation: {terminal_text(fv.obligation)}" if fv.obligation else ""))
    elif fv.obligation:
        lines.append(f"  obligation: {terminal_text(fv.obligation)}")
    if v.robustness_at is not None and v.robustness is not None and math.isfinite(v.robustness):
        lines.append(f"  robustness {robustness_text(v.robustness)} at tick "
                     f"{v.robustness_at.tick} ({format_offset(v.robustness_at.time_ns, st)})")
    lt = (f"; deciding message log time {fv.at.log_time_ns} ns"
          if fv.at.log_time_ns is not None else "")
    lines.append(f"  {terminal_text(fv.reason)}; missed at tick {fv.at.tick} "
                 f"({format_offset(fv.at.time_ns, st)} on the {clock}{lt})")
    if la.allowance_ns:
        lines.append(f"  read with the allowance: {allowance_text(la.allowance_ns)} (an answer "
                     "seen within it after a tick is judged at that tick; times of those "
                     "topics are their log times less it)")
    if v.triggers is not None and v.violations:
        lines.append(f"  {v.violations} of {v.triggers} triggers failed")
    head.append("\n".join(lines))
    return head


def _print_violation_verbose(console, la: LogAudit, v: Verdict,
                             tool_id: str | None = None) -> None:
    """Violation ``v``'s :func:`_violation_text`, then the values around it (``--verbose``)."""
    console.print(_violation_text(la, v, tool_id), highlight=False)
    st = la.start_time_ns
    fv = v.first_violation
    if fv is None or not v.values:
        return
    t = Table(show_header=True, header_style="bold", box=None, pad_edge=False)
    t.add_column("tick", justify="right")
    t.add_column("time", justify="right")
    names = list(v.values)
    topics = list(v.sources)
    heads = [terminal_text(h) for h in _headers(names) + [f"{tp} @" for tp in topics]]
    for h in heads:
        t.add_column(h, justify="right", no_wrap=True, min_width=len(h))
    rows = list(zip(*[v.values[n] for n in names])) if names else []
    marks = {fv.at.tick: "<- missed"}
    if fv.trigger is not None:
        marks.setdefault(fv.trigger.tick, "<- trigger")
        if fv.trigger.tick == fv.at.tick:
            marks[fv.at.tick] = "<- trigger, missed"
    t.add_column("", no_wrap=True, min_width=18)
    prev = None
    for k, row in enumerate(rows):
        tick, ns = row[0][0], row[0][1]
        if prev is not None and tick != prev + 1:
            t.add_row("…", f"{tick - prev - 1} ticks", *[""] * (len(heads) + 1))
        prev = tick
        cells = [str(tick), format_offset(ns, st)] + [_value(c[2]) for c in row]
        for tp in topics:
            held = v.sources[tp][k][2]
            cells.append(format_offset(held, st))
        cells.append(marks.get(tick, ""))
        t.add_row(*cells)
    console.print(t)


def gap_text(g: dict, st: int | None) -> str:
    """One gap of the audit JSON (:func:`fretc.audit.gaps.gap_json`) in words: its cause,
    log-time span (s from ``st``), the messages it counts and the topics it may hold."""
    span = _span(g.get("start_ns"), g.get("end_ns"), st)
    n = g.get("messages")
    count = f"{n} message{'s' if n != 1 else ''} " if n else ""
    topics = g.get("topics")
    on = (f" of {', '.join(topics[:3])}{' ...' if len(topics) > 3 else ''}" if topics
          else " of every topic")
    return f"{count}{g.get('cause') or 'gap'}{span}{on}"


def _span(lo: int | None, hi: int | None, st: int | None) -> str:
    """A log-time span (ns) in words, seconds from ``st``; an end at
    :data:`fretc.logs.recorded_gaps.RUN_END` (a publisher gone for good) is the end of the
    run."""
    end = "the end of the run" if hi is not None and hi >= RUN_END else None
    if lo is None:
        return " from the start" + (f" to {end}" if end else "")
    if end:
        return f" from {format_offset(lo, st)} to {end}"
    if hi is None or hi == lo:
        return f" at {format_offset(lo, st)}"
    return f" over {format_offset(lo, st)} .. {format_offset(hi, st)}"


def damage_summary(la: LogAudit) -> str:
    """What damaged a partial log and how it was judged, in one sentence: the damage
    problems (kind and log-time span, seconds from the first tick), the gaps judged as
    unknown ticks or bridged, and where a cut ends what was read."""
    st = la.start_time_ns
    kinds = ("truncated", "chunk_crc", "chunk_corrupt", "corrupt_record", "summary_corrupt",
             "data_crc", "unknown_channel", "out_of_order", "dropout", "connection_gap",
             "publisher_left", LEFT_FOR_GOOD, RECORDED_GAPS)
    parts = []
    for p in la.problems:
        if p.get("kind") not in kinds:
            continue
        lo, hi = p.get("log_time_ns"), p.get("end_time_ns")
        span = _span(lo, hi, st) if lo is not None else ""
        parts.append(f"{p['kind']}{span}")
        if len(parts) >= 3:
            break
    more = sum(n for k, n in la.problem_counts.items() if k.split(" ")[0] in kinds) - len(parts)
    what = ", ".join(parts) + (f" and {more} more" if more > 0 else "") or "damaged"
    said = []
    gaps = [g for g in la.gaps if not g.get("bridged")]
    bridged = [g for g in la.gaps if g.get("bridged")]
    if gaps:
        listed = "; ".join(gap_text(g, st) for g in gaps[:4])
        said.append(f"{len(gaps)} gap{'s' if len(gaps) != 1 else ''} ({listed}"
                    f"{' ...' if len(gaps) > 4 else ''}): their ticks are unknown, the log "
                    "is judged on after them")
    if bridged:
        listed = "; ".join(gap_text(g, st) for g in bridged[:4])
        said.append(f"{len(bridged)} gap{'s' if len(bridged) != 1 else ''} bridged, the value "
                    f"before held over {'them' if len(bridged) != 1 else 'it'} ({listed}"
                    f"{' ...' if len(bridged) > 4 else ''})")
    if la.cut_time_ns is not None:
        cut = f"nothing read after {format_offset(la.cut_time_ns, st)} (cut)"
        if la.ticks_after_damage:
            cut += f", {la.ticks_after_damage} ticks after it not judged"
        said.append(cut)
    if not said:
        said.append("no message lost" if not la.damage_cut else "judged on after it")
    return f"the log is damaged ({what}); " + "; ".join(said)
