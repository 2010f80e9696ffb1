"""One verdict of the audit JSON (``fretc-audit/1``, :mod:`fretc.audit.verdict`) as the
report shows it: its matrix cell, its witness as (label, text) facts, and the table of the
values sampled around a violation. Plain functions of the JSON objects, no I/O.
"""

from __future__ import annotations

import json
from typing import Any

from fretc.common.units import format_offset, format_seconds
from fretc.logs.allowance import allowance_text

__all__ = ["verdict_for", "cell_label", "witness", "values_table", "format_value"]


def format_value(v: Any) -> str:
    """A sampled value as reports print it: booleans ``T``/``F``, None ``-``, numbers with
    every digit they need to read back as the same float (Python's shortest ``repr``,
    ``1.000158``, never ``1`` for it: a value beside a threshold shows which side it is on;
    a whole number without ``.0``)."""
    if isinstance(v, bool):
        return "T" if v else "F"
    if isinstance(v, float):
        text = repr(v)
        return text[:-2] if text.endswith(".0") else text
    if v is None:
        return "-"
    return str(v)


_fmt_value = format_value


def verdict_for(la: dict, i: int, r: dict) -> dict | None:
    """The verdict of requirement ``r`` (index ``i`` of ``requirements``) on log ``la``:
    verdicts are in requirement order; matched by id (and source when ids repeat)."""
    vs = la.get("verdicts") or []
    if i < len(vs) and vs[i].get("requirement") == r.get("id"):
        return vs[i]
    same = [x for x in vs if x.get("requirement") == r.get("id")]
    if len(same) > 1:
        same = [x for x in same if x.get("source") == r.get("source")]
    return same[0] if len(same) == 1 else None


def cell_label(v: dict | None) -> tuple[str, str]:
    """(verdict class, short text) of a matrix cell: the verdict, and for a violation the
    time of the first one (``violated @ 12.300 s``); ``("none", "not audited")`` for no
    verdict."""
    if v is None:
        return "none", "not audited"
    verdict = v.get("verdict", "error")
    text = verdict
    fv = v.get("first_violation")
    if verdict == "violated" and fv and fv.get("tick_time_s", fv.get("log_time_s")) is not None:
        text += f" @ {fv.get('tick_time_s', fv.get('log_time_s')):.3f} s"
    return verdict, text


def _violation_facts(fv: dict, start_ns: int | None) -> list[tuple[str, str]]:
    """The facts of a first violation: where it was decided, its trigger, scope interval,
    response window, obligation and reason; times in seconds on the log clock (since
    ``start_ns``, the log's start), the deciding message's too."""
    out: list[tuple[str, str]] = []
    tick_s = fv.get("tick_time_s", fv.get("log_time_s"))
    base = fv.get("tick_time_base") or "log"
    decided = format_offset(fv.get("log_time_ns"), start_ns, missing="")
    if not decided and fv.get("log_time_s") is not None:
        decided = format_seconds(fv.get("log_time_s"))
    out.append(("first violation", f"tick {fv['tick']} at {format_seconds(tick_s)} on the {base} "
                                    "clock" + (f" (deciding message at {decided} on the log "
                                               "clock)" if decided and base != "log" else "")))
    if fv.get("allowance_ns"):  # (read with a reaction allowance: never shown without it)
        out.append(("allowance", allowance_text(fv["allowance_ns"]) + " (an answer seen "
                    "within it after a tick is judged at that tick)"))
    t = fv.get("trigger")
    if t:
        out.append(("trigger", f"tick {t['tick']} at {format_seconds(t.get('time_s'))}"))
    sc = fv.get("scope_interval")
    if sc:
        out.append(("scope interval", f"ticks [{sc['start']['tick']}, {sc['end']['tick']}]"
                    f" = {format_seconds(sc['start'].get('time_s'))} .. "
                    f"{format_seconds(sc['end'].get('time_s'))}"))
    w = fv.get("window")
    if w:
        hi = format_seconds(w.get("end_time_s"), missing="past the end")
        out.append(("response window", f"ticks [{w['start_tick']}, {w['end_tick']}] = "
                    f"{format_seconds(w.get('start_time_s'))} .. {hi}"))
    if fv.get("obligation"):
        out.append(("obligation", fv["obligation"]))
    if fv.get("reason"):
        out.append(("reason", fv["reason"]))
    return out


def witness(v: dict, start_ns: int | None = None) -> list[tuple[str, str]]:
    """(label, text) facts of a verdict's witness: the first violation, the LTL3 verdict,
    the trigger counts, the later violations (at most 20 listed), the worst margin, the
    ticks, notes and error. Every time is in seconds on the log clock (since the log's
    start, ``start_ns``, the integer ns of its first message, which the run names once);
    no fact repeats an absolute log time."""
    fv = v.get("first_violation")
    out = _violation_facts(fv, start_ns) if fv else []
    l3 = v.get("ltl3") or {}
    if l3.get("status"):
        txt = l3["status"]
        if l3.get("tick") is not None:
            txt += f" at tick {l3['tick']} ({format_seconds(l3.get('time_s'))})"
        out.append(("LTL3 (ft_inf)", txt))
    if v.get("triggers") is not None:
        out.append(("triggers", f"{v['triggers']} in {v.get('intervals')} scope interval(s), "
                                f"{v.get('violations')} failed"))
    listed = v.get("violation_list") or []
    if len(listed) > 1:
        # one entry per tick where obligations were missed (many triggers of one scope
        # interval can be missed at its end), with how many
        ticks: dict[int, list] = {}
        for x in listed:
            ticks.setdefault(x["violation"]["tick"], [x["violation"], 0])[1] += 1
        items = list(ticks.values())
        shown = ", ".join(f"{format_seconds(w['time_s'])} (#{w['tick']})"
                          + (f" x{n}" if n > 1 else "") for w, n in items[:20])
        more = len(items) - 20
        total = v.get("violations") or len(listed)
        out.append(("violations at", shown + (f", ... ({more} more ticks listed)"
                                              if more > 0 else "")
                    + (f"; {total} in all" if total > sum(n for _w, n in items[:20]) else "")))
    rob = v.get("robustness") or {}
    if rob.get("tick") is not None and isinstance(rob.get("value"), (int, float)):
        out.append(("worst margin", f"{_signed(rob['value'])} at tick {rob['tick']} "
                                    f"({format_seconds(rob.get('time_s'))})"))
    out.append(("ticks", f"{v.get('ticks_evaluated')} evaluated"
                         + (f", {v['warmup_ticks']} warm-up" if v.get("warmup_ticks") else "")
                         + (f" ({v['engine']} engine)" if v.get("engine") else "")))
    for n in v.get("notes") or []:
        out.append(("note", n))
    if v.get("error"):
        out.append(("error", v["error"]))
    return out


def _signed(value: float | str) -> str:
    """A margin as the report prints it: signed, 4 significant digits, or +inf/-inf."""
    x = float(value) + 0.0
    if x != x or x in (float("inf"), float("-inf")):
        return {float("inf"): "+inf", float("-inf"): "-inf"}.get(x, "nan")
    return f"{x:+.4g}"


def _rows_by_tick(v: dict) -> dict[int, dict]:
    """tick -> ``{tick, time_s, time_ns, cells}``: the sampled values (``cells[variable]``)
    and the log time of the message held on each topic (``cells["@" + topic]``)."""
    ticks: dict[int, dict] = {}
    for name, rows in (v.get("values") or {}).items():
        for r in rows:
            row = ticks.setdefault(r["tick"], {"tick": r["tick"], "time_s": r.get("time_s"),
                                               "time_ns": r.get("time_ns"), "cells": {}})
            row["cells"][name] = r.get("value")
    for topic, rows in (v.get("sources") or {}).items():
        for r in rows:
            row = ticks.setdefault(r["tick"], {"tick": r["tick"], "time_s": r.get("time_s"),
                                               "time_ns": r.get("time_ns"), "cells": {}})
            lt = r.get("message_log_time_ns")
            row["cells"]["@" + topic] = lt
    return ticks


def _witness_marks(v: dict) -> dict[int, list[str]]:
    """tick -> what happened there: trigger, violation, the LTL3 verdict."""
    fv = v.get("first_violation") or {}
    marks: dict[int, list[str]] = {}
    if fv.get("trigger"):
        marks.setdefault(fv["trigger"]["tick"], []).append("trigger")
    if fv.get("tick") is not None:
        marks.setdefault(fv["tick"], []).append("violation")
    l3 = v.get("ltl3") or {}
    if l3.get("status") in ("violated", "satisfied") and l3.get("tick") is not None:
        marks.setdefault(l3["tick"], []).append(f"LTL3 {l3['status']}")
    return marks


def values_table(v: dict, start_ns: int | None) -> dict:
    """Columns and rows of a violation's sampled values (tick, time, variables, held
    message time of each topic) with the ticks of the witness marked.

    Returns:
        ``{"columns": [{key, label, kind: variable | topic}], "rows": [{tick, time_s,
        time_ns, cells: [{raw (JSON), text, bool}], marks, gap, window}]}``; ``gap`` is set
        on a row whose tick does not follow the previous row's, ``window`` on rows inside
        the response window.
    """
    values = v.get("values") or {}
    sources = v.get("sources") or {}
    ticks = _rows_by_tick(v)
    marks = _witness_marks(v)
    w = (v.get("first_violation") or {}).get("window")
    columns = [{"key": n, "label": n, "kind": "variable"} for n in values]
    columns += [{"key": "@" + t, "label": f"{t} @", "kind": "topic"} for t in sorted(sources)]
    rows = []
    prev = None
    for k in sorted(ticks):
        row = ticks[k]
        cells = []
        for c in columns:
            raw = row["cells"].get(c["key"])
            if c["kind"] == "topic":
                shown = format_offset(raw, start_ns)
            else:
                shown = _fmt_value(raw)
            cells.append({"raw": json.dumps(raw), "text": shown,
                          "bool": raw if isinstance(raw, bool) else None})
        in_window = bool(w and w["start_tick"] <= k <= w["end_tick"])
        rows.append({"tick": k, "time_s": format_seconds(row["time_s"]), "time_ns": row["time_ns"],
                     "cells": cells, "marks": ", ".join(marks.get(k, [])),
                     "gap": prev is not None and k != prev + 1, "window": in_window})
        prev = k
    return {"columns": columns, "rows": rows}
