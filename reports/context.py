"""The report's data record (``fretc report``): everything the templates
(``templates/report.html.j2``, ``templates/report.md.j2``) show, built from the audit document
(``fretc-audit/1``) and the requirement traces (:mod:`fretc.reports.trace`) as plain dicts
and lists: the header and inputs, the runs, one row per requirement with its matrix cells,
the violations with their timelines (:mod:`fretc.reports.timeline`), and the coverage.

Deterministic: the same inputs give the same record except the generation line (UTC;
``SOURCE_DATE_EPOCH`` fixes it).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import os
import re
from importlib.metadata import PackageNotFoundError, version
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from fretc.common.units import format_seconds

from fretc.reports.export_results import requirement_results
from fretc.reports.margin import margin_svg
from fretc.reports.rollup import rollups
from fretc.reports.terminal import damage_summary, robustness_text
from fretc.reports.trace import FIELD_NAMES, ModuleInfo, RequirementTrace, resolve_input, split_source
from fretc.reports.verdicts import cell_label, values_table, verdict_for, witness
from fretc.reports.timeline import COLORS, timeline_svg

__all__ = ["report_context", "GENERATED_PREFIX"]

#: Every report line that varies between runs starts with this text (HTML: inside a
#: ``<p class="generated">``; Markdown: the line itself).
GENERATED_PREFIX = "Generated at "

#: What each exit code of the audit means, as the report's summary says it.
_EXIT_MEANING = {0: "every verdict satisfied or vacuous", 1: "a requirement is violated",
                 2: "something could not be audited",
                 3: "no violation, but a log is partial or had data problems, or a verdict is "
                    "unknown"}


def _sha256_file(path: Path) -> str | None:
    try:
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
        return h.hexdigest()
    except OSError:
        return None


def _slug(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_]+", "-", str(text)).strip("-").lower()
    return s or "x"


class _Anchors:
    """Unique, deterministic HTML ids."""

    def __init__(self) -> None:
        self.used: set[str] = set()

    def make(self, *parts: str) -> str:
        base = "-".join(_slug(p) for p in parts)
        name, k = base, 2
        while name in self.used:
            name, k = f"{base}-{k}", k + 1
        self.used.add(name)
        return name


def _tick_text(tick: dict | None) -> str:
    if not tick:
        return "-"
    if tick.get("period_ns"):
        return f"every {tick['period_ns'] / 1e6:g} ms (sample-and-hold)"
    if tick.get("topic"):
        return f"one per {tick['topic']} message"
    return "-"


def _generated_line(when: _dt.datetime | None = None) -> str:
    if when is None:
        epoch = os.environ.get("SOURCE_DATE_EPOCH")
        if epoch and epoch.strip().isdigit():
            when = _dt.datetime.fromtimestamp(int(epoch), tz=_dt.UTC)
        else:
            when = _dt.datetime.now(tz=_dt.UTC)
    return GENERATED_PREFIX + when.astimezone(_dt.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def _version() -> str:
    try:
        return version("fretc")
    except PackageNotFoundError:  # not installed
        return "dev"


def _damage_text(la: dict) -> str:
    """Where and how a partial log is damaged, and how far it was judged
    (:func:`fretc.reports.terminal.damage_summary` on the JSON document)."""
    fields = ("start_time_ns", "damage_time_ns", "ticks_after_damage", "damage_cut",
              "cut_time_ns")
    ns = SimpleNamespace(problems=la.get("problems") or [],
                         problem_counts=la.get("problem_counts") or {},
                         gaps=la.get("gaps") or [], **{k: la.get(k) for k in fields})
    return damage_summary(ns)  # type: ignore[arg-type]  # (the fields it reads, from the JSON)


class _Inputs:
    """Where the document's relative paths are looked up, for the SHA-256 of the files."""

    def __init__(self, base: Path | None, json_dir: Path | None) -> None:
        self.base, self.json_dir = base, json_dir

    def file_info(self, p: str) -> dict:
        path = resolve_input(p, self.base, self.json_dir)
        return {"path": p, "sha256": _sha256_file(path) if path is not None and path.is_file()
                else None}


def _run_rows(logs: list[dict], anchors: _Anchors, annotated: dict[int, dict] | None,
              inputs: _Inputs) -> list[dict]:
    """One record per run (log object of the document), in order."""
    runs = []
    for j, la in enumerate(logs):
        name = Path(la.get("log", f"log{j}")).name
        st = la.get("start_time_ns")
        dur = None
        if st is not None and la.get("end_time_ns") is not None:
            dur = (la["end_time_ns"] - st) / 1e9
        problems = [f"{k}: {n}" for k, n in sorted((la.get("problem_counts") or {}).items())]
        ann = (annotated or {}).get(j)
        runs.append({
            "index": j, "anchor": anchors.make("run", Path(name).stem), "name": name,
            "name_parts": re.split(r"(?<=[_.-])", Path(name).stem),
            "path": la.get("log"), "kind": la.get("kind"),
            "sha256": (inputs.file_info(la["log"])["sha256"] if la.get("log") else None),
            "duration": format_seconds(dur),
            "start_time_ns": st, "ticks": la.get("ticks_evaluated"),
            "warmup": la.get("warmup_ticks"), "waiting_for": la.get("waiting_for") or [],
            "missing_topics": la.get("missing_topics") or [],
            "tick": _tick_text(la.get("tick")), "time_base": la.get("time_base") or "-",
            "messages": sorted((la.get("messages") or {}).items()),
            "problems": problems, "partial": bool(la.get("partial")),
            "damage": _damage_text(la) if la.get("partial") else None,
            "error": la.get("error"), "engine": la.get("engine"),
            "annotated": ann,
        })
    return runs


def _requirement_fields(r: dict, rt: RequirementTrace | None, bvars: dict,
                        id_anchor: dict[str, str]) -> dict:
    """The requirement part of a requirement's record (all but its cells, monitor and AJPF
    property): the audit JSON's, completed by the trace when there is one."""
    file, line = split_source(r.get("source", ""))
    parent = rt.parent if rt is not None else None
    variables = []
    for name in (r.get("variables") or (rt.variables if rt else [])):
        b = bvars.get(name)
        variables.append({"name": name, "expr": b["expr"] if b else None,
                          "where": f"{b['source']}:{b['line']}" if b else None,
                          "topics": ", ".join(b.get("topics") or []) if b else ""})
    return {
        "id": r.get("id"), "text": r.get("text"), "source": r.get("source"),
        "file": file, "line": line, "key": r.get("key") or (rt.key if rt else None),
        "parent": parent, "parent_anchor": id_anchor.get(parent) if parent else None,
        "rationale": rt.rationale if rt else None,
        "fields": [{"text": t, "field": f} for t, f in (rt.fields if rt else
                                                        [(r.get("text", ""), None)])],
        "formulas": ([("ft", rt.ft), ("ft_inf", rt.ft_inf), ("pt", rt.pt)]
                     if rt is not None and rt.ft is not None else []),
        "spot": ([("ft", rt.ft_spot), ("ft_inf", rt.ft_inf_spot)]
                 if rt is not None and rt.ft_spot is not None else []),
        "variables": variables, "tick_period": (f"{r['tick_period_s'] * 1000:g} ms"
                                                if r.get("tick_period_s") else "-"),
        "duration_ticks": r.get("duration_ticks"),
        "monitor": None, "ajpf": None,
        "warnings": list(rt.warnings) if rt else [],
        "notes": list(r.get("notes") or []), "error": r.get("error"),
        "reading": rt.reading if rt else None, "diagram": rt.diagram_svg if rt else None,
        "semantics": rt.semantics_svg if rt else None,
        "changed": rt.changed if rt else "not found in the requirement files: shown from "
                                         "the audit JSON only",
        "cells": [],
    }


def _monitor_fields(rt: RequirementTrace, modules: dict[str, ModuleInfo]) -> dict:
    """The ``monitor`` and ``ajpf`` parts of a traced requirement's record."""
    mod = modules.get(rt.module) if rt.module else None
    monitor = {"class_name": rt.class_name, "module": rt.module,
               "module_anchor": f"mod-{_slug(rt.module)}" if rt.module else None,
               "module_sha256": mod.sha256 if mod else None,
               "module_digest": mod.digest if mod else None,
               "source_hash": rt.source_hash, "class_source": rt.class_source,
               "class_lines": len(rt.class_source.splitlines())}
    return {"monitor": monitor, "ajpf": {"label": rt.ajpf_label, "formula": rt.ajpf_formula,
                                         "reason": rt.ajpf_reason}}


def _violation(v: dict, la: dict, r: dict, rt: RequirementTrace | None, rc: dict, run: dict,
               anchor: str, witness_facts: list, period_ns: int | None) -> dict:
    """The record of one violation: its timeline SVG, witness, values table and times."""
    fv = v["first_violation"]
    svg = timeline_svg(v, la, period_ns=(la.get("tick") or {}).get("period_ns") or period_ns,
                       thresholds=rt.thresholds if rt else (),
                       title=f"{r.get('id')} violated on {la.get('log')} at "
                             f"{format_seconds(fv.get('tick_time_s', fv.get('log_time_s')))}")
    trig = fv.get("trigger") or {}
    l3 = v.get("ltl3") or {}
    return {
        "anchor": anchor, "req": rc, "run": run, "svg": svg,
        "svg_file": f"timelines/{anchor}.svg", "witness": witness_facts,
        "verdict": v, "table": values_table(v, la.get("start_time_ns")),
        "violation_ns": fv.get("log_time_ns"),
        "violation_s": format_seconds(fv.get("tick_time_s", fv.get("log_time_s"))),
        "trigger_ns": trig.get("time_ns"), "trigger_s": format_seconds(trig.get("time_s")),
        "ltl3_status": l3.get("status"), "ltl3_ns": l3.get("time_ns"),
        "ltl3_s": format_seconds(l3.get("time_s")),
        "partial": bool(v.get("partial")),
    }


def _add_cells(rc: dict, r: dict, rt: RequirementTrace | None, logs: list[dict],
               runs: list[dict], anchors: _Anchors, period_ns: int | None,
               violations: list[dict]) -> None:
    """Append the requirement's matrix cells (one per run) to ``rc["cells"]`` and its
    violations to ``violations``; ``rc["margin_svg"]`` its margin over time in every run."""
    margins: list[tuple] = []
    for j, la in enumerate(logs):
        v = verdict_for(la, rc["index"], r)
        cls, label = cell_label(v)
        run = runs[j]
        row_anchor = f"{rc['anchor']}-{run['anchor']}"
        word, _, at = label.partition(" @ ")
        cell: dict[str, Any] = {"run": j, "verdict": cls, "label": label, "word": word,
                "at": ("@ " + at) if at else "",
                "partial": bool(v and v.get("partial")), "row_anchor": row_anchor,
                "href": "#" + row_anchor,
                "witness": witness(v, la.get("start_time_ns")) if v else [],
                "violation_anchor": None, "log_time_ns": None}
        if v is not None and cls == "violated" and v.get("first_violation"):
            va = anchors.make("v", r.get("id", ""), Path(run["name"]).stem)
            cell["violation_anchor"] = va
            cell["href"] = "#" + va
            cell["log_time_ns"] = v["first_violation"].get("log_time_ns")
            violations.append(_violation(v, la, r, rt, rc, run, va, cell["witness"],
                                         period_ns))
        rob = (v or {}).get("robustness") or {}
        cell["robustness"] = robustness_text(rob.get("value"), "-")
        margins.append((run["name"], rob.get("margin") or [],
                        (rob.get("time_s"), rob.get("value")) if rob.get("tick") is not None
                        else None))
        rc["cells"].append(cell)
    rc["margin_svg"] = margin_svg(margins, f"{r.get('id')}: margin over time")


def _requirement_rows(reqs: list[dict], logs: list[dict], runs: list[dict],
                      traces: dict[int, RequirementTrace], modules: dict[str, ModuleInfo],
                      bindings: dict, anchors: _Anchors) -> tuple[list[dict], list[dict]]:
    """(one record per requirement with its cells, the violations in matrix order)."""
    bvars = bindings.get("variables") or {}
    period_ns = (bindings.get("tick") or {}).get("period_ns")
    req_ctx = []
    id_anchor: dict[str, str] = {}
    for i, r in enumerate(reqs):
        a = anchors.make("req", r.get("id", f"r{i}"))
        id_anchor.setdefault(str(r.get("id")), a)
        req_ctx.append({"index": i, "anchor": a})
    violations: list[dict] = []
    for i, r in enumerate(reqs):
        rt = traces.get(i)
        rc = req_ctx[i]
        rc.update(_requirement_fields(r, rt, bvars, id_anchor))
        if rt is not None:
            rc.update(_monitor_fields(rt, modules))
        _add_cells(rc, r, rt, logs, runs, anchors, period_ns, violations)
    return req_ctx, violations


def _trigger_coverage(req_ctx: list[dict], reqs: list[dict], logs: list[dict]
                      ) -> tuple[list[dict], list[dict]]:
    """(requirements audited somewhere whose trigger never fired, per requirement the
    trigger counts of each run: ``-`` not audited, ``?`` unknown)."""
    never = []
    trig_rows = []
    for rc in req_ctx:
        counts = []
        audited = 0
        fired = False
        unknown = False
        scope_entered = False
        for la in logs:
            v = verdict_for(la, rc["index"], reqs[rc["index"]])
            if v is None or v.get("verdict") == "error":
                counts.append("-")
                continue
            audited += 1
            t = v.get("triggers")
            if t is None:
                unknown = True
                counts.append("?")
            else:
                counts.append(str(t))
                fired = fired or t > 0
                scope_entered = scope_entered or (v.get("intervals") or 0) > 0
            if v.get("verdict") == "violated":
                fired = True
        trig_rows.append({"req": rc, "counts": counts})
        if audited and not fired and not unknown:
            never.append({"req": rc, "why": ("the scope was never entered" if not scope_entered
                                             else "the trigger never fired"),
                          "runs": audited})
    return never, trig_rows


def _missing_topics(req_ctx: list[dict], reqs: list[dict], logs: list[dict],
                    runs: list[dict], bvars: dict) -> tuple[list[dict], list[str]]:
    """(per run the bound topics it misses, the bound topics every audited run misses).

    The bound topics are those of the audited requirements' variables; a run misses one
    when it never had a message on it (``missing_topics``: in the log but silent) or none
    was read (the topic is not in the log: those requirements are ``error`` there)."""
    used_vars = {n for r in reqs for n in (r.get("variables") or [])}
    bound: dict[str, list[str]] = {}
    for n, b in sorted(bvars.items()):
        if used_vars and n not in used_vars:
            continue
        for t in b.get("topics") or []:
            bound.setdefault(t, []).append(n)
    missing = []
    for run, la in zip(runs, logs):
        if la.get("error"):
            continue
        read = la.get("messages") or {}
        silent = set(la.get("missing_topics") or [])
        for topic in sorted(set(bound) | silent):
            if topic not in silent and read.get(topic, 0) > 0:
                continue
            users = bound.get(topic, [])
            affected = [rc["id"] for rc in req_ctx
                        if any(vv["name"] in users for vv in rc["variables"])]
            missing.append({"run": run, "topic": topic, "variables": users,
                            "requirements": affected,
                            "how": ("in the log, never published" if topic in silent
                                    else "no message read (not in the log)")})
    never_in_any = sorted(t for t in bound
                          if logs and all(any(m["topic"] == t and m["run"] is run
                                              for m in missing)
                                          for run, la in zip(runs, logs)
                                          if not la.get("error")))
    return missing, never_in_any


def _coverage(req_ctx: list[dict], reqs: list[dict], logs: list[dict], runs: list[dict],
              bvars: dict) -> dict:
    """The coverage section: requirements never triggered, trigger counts, missing topics,
    partial and failed runs, error cells, runs with warm-up ticks."""
    never, trig_rows = _trigger_coverage(req_ctx, reqs, logs)
    missing, never_in_any = _missing_topics(req_ctx, reqs, logs, runs, bvars)
    return {"never_triggered": never, "triggers": trig_rows, "missing": missing,
            "silent_topics": never_in_any,
            "partial": [r for r in runs if r["partial"]],
            "log_errors": [r for r in runs if r["error"]],
            "errors": [(rc, c) for rc in req_ctx for c in rc["cells"]
                       if c["verdict"] == "error"],
            "warmup": [r for r in runs if r["warmup"]]}


def _parents(doc: dict, req_ctx: list[dict]) -> list[dict]:
    """The parent requirements (those others refine) with their rolled-up verdicts
    (:mod:`fretc.reports.rollup`), each id linked to its section when the report has one;
    each requirement record of ``req_ctx`` gets its ``rollup`` line."""
    anchor = {rc["id"]: rc["anchor"] for rc in req_ctx}
    rolled = rollups(doc, {k: r.verdict for k, r in requirement_results(doc, "", "").items()})
    for rc in req_ctx:
        rc["rollup"] = rolled[rc["id"]].text() if rc["id"] in rolled else None

    def link(rid: str) -> dict:
        return {"id": rid, "anchor": anchor.get(rid)}
    return [{"id": ru.id, "anchor": anchor.get(ru.id), "own": ru.own, "verdict": ru.verdict,
             "text": ru.text(), "decided_by": ru.decided_by,
             "path": [link(x) for x in ru.path], "children": [link(c) for c in ru.children]}
            for ru in rolled.values()]


def report_context(doc: dict, traces: dict[int, RequirementTrace],
                   modules: dict[str, ModuleInfo], *, notes: Sequence[str] = (),
                   annotated: dict[int, dict] | None = None, title: str | None = None,
                   base: Path | None = None, json_dir: Path | None = None,
                   generated: str | None = None) -> dict:
    """Everything the templates show, as plain dicts and lists (see the templates).

    Args:
        doc: the audit document.
        traces, modules, notes: from :func:`fretc.reports.trace.trace_requirements`.
        annotated: log index -> ``{"path": annotated MCAP (relative to the report),
            "events": n, "partial": bool, "damage": str}``.
        title: the report title.
        base, json_dir: where the log, requirement and binding paths are looked up for their
            SHA-256 (in this order; default the current folder).
        generated: the generation line (default: now, or ``SOURCE_DATE_EPOCH``).
    """
    anchors = _Anchors()
    inputs = _Inputs(base, json_dir)
    reqs = doc.get("requirements") or []
    logs = doc.get("logs") or []
    bindings = doc.get("bindings") or {}
    runs = _run_rows(logs, anchors, annotated, inputs)
    req_ctx, violations = _requirement_rows(reqs, logs, runs, traces, modules, bindings,
                                            anchors)
    coverage = _coverage(req_ctx, reqs, logs, runs, bindings.get("variables") or {})
    parents = _parents(doc, req_ctx)
    req_files: list[dict[str, Any]] = []
    for rc in req_ctx:
        if rc["file"] and rc["file"] not in [f["path"] for f in req_files]:
            req_files.append(inputs.file_info(rc["file"]))
    bind_files = [inputs.file_info(s) for s in bindings.get("sources") or []]
    summary = doc.get("summary") or {}
    return {
        "title": title or "fretc traceability report",
        "generated": generated or _generated_line(),
        "version": _version(), "schema": doc.get("schema"),
        "summary": summary,
        "exit_meaning": _EXIT_MEANING.get(summary.get("exit_code", -1), ""),
        "requirement_files": req_files, "binding_files": bind_files,
        "tick": _tick_text(bindings.get("tick")), "time_base": bindings.get("time_base") or "-",
        "runs": runs, "requirements": req_ctx, "violations": violations, "parents": parents,
        "coverage": coverage, "modules": [
            {"name": m.name, "sha256": m.sha256, "digest": m.digest, "text": m.text,
             "anchor": f"mod-{_slug(m.name)}", "lines": len(m.text.splitlines())}
            for m in modules.values()],
        "notes": list(notes), "field_names": FIELD_NAMES,
        "colors": COLORS,
    }
