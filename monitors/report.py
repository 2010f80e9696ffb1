"""Traceability reports (``fretc report``): requirement -> formulas -> monitor -> verdict, with
the evidence of every recorded run, as one self-contained HTML page and the same content in
Markdown.

::

    fretc report -r requirements/ traces/ -o report/ [--annotate annotated/]   # runs the audit
    fretc report --from-json audit.json -o report/ [--annotate annotated/]     # reads one

Input is the audit's JSON document (schema ``fretc-audit/1``, :mod:`monitors.report_model`);
what it does not carry (parent, rationale, the FRETish field spans, ft / ft_inf / pt, the
generated monitor module, the AJPF property) comes from compiling the requirement files the
audit names (``requirements[].source``), exactly as ``fretc audit`` does
(:func:`monitors.audit.load_plan`). With ``--from-json`` those files are looked up relative
to ``--base`` (default: the current folder, then the JSON's folder); a requirement whose text
differs from the audited one is flagged, and one whose file is gone is shown from the JSON
alone.

Output folder::

    report.html        self-contained: inline CSS and SVG, no script, no external asset
    report.md          the same content (timelines as image links to timelines/)
    audit.json         the audit document the report was made from
    timelines/*.svg    one timeline per violation (the same SVG as inlined in the HTML)

The report holds: the summary and inputs (files with SHA-256); the matrix requirements x runs
(verdict of each cell, linking to its evidence); per requirement its id, parent, rationale,
FRETish text with the fields (scope, condition, component, timing, response) marked from the
AST spans, FRET template key, ft / ft_inf / pt, the monitor class and module with their
hashes, the AJPF property label and formula (or why there is none), and per run the verdict
and witness; per violation a timeline (:mod:`monitors.timeline`) and the sampled values;
coverage (requirements never triggered, runs missing a bound topic, damaged runs); the runs;
the generated monitor modules.

Deterministic: the same inputs give byte-identical files except the one line stating the
generation time (UTC; ``SOURCE_DATE_EPOCH`` fixes it).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from fretish.errors import FretcError
from fretish.units import format_seconds as _fmt_s

from .report_model import SCHEMA

__all__ = ["ReportError", "RequirementTrace", "ModuleInfo", "ReportFiles", "load_audit_json",
           "trace_requirements", "report_context", "render_html", "render_markdown",
           "write_report", "marked_fields", "FIELD_NAMES",
           "GENERATED_PREFIX"]

#: The FRETish fields marked in the requirement text, in sentence order.
FIELD_NAMES = ("scope", "condition", "component", "probability", "timing", "response")
#: Every report line that varies between runs starts with this text (HTML: inside a
#: ``<p class="generated">``; Markdown: the line itself).
GENERATED_PREFIX = "Generated at "
VERDICT_WORDS = {"satisfied": "satisfied", "vacuous": "vacuous", "violated": "violated",
                 "unknown": "unknown", "error": "error"}


class ReportError(FretcError):
    """The report cannot be made: unreadable or wrong-schema JSON, unwritable output."""


# --------------------------------------------------------------------------- helpers
def _sha256_file(path: Path) -> Optional[str]:
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
        self.used: set = set()

    def make(self, *parts: str) -> str:
        base = "-".join(_slug(p) for p in parts)
        name, k = base, 2
        while name in self.used:
            name, k = f"{base}-{k}", k + 1
        self.used.add(name)
        return name


def _fmt_value(v: Any) -> str:
    if isinstance(v, bool):
        return "T" if v else "F"
    if isinstance(v, float):
        return f"{v:.6g}"
    if v is None:
        return "-"
    return str(v)


def _split_source(src: str) -> Tuple[str, Optional[int]]:
    """``"file:line"`` -> (file, line)."""
    file, sep, line = (src or "").rpartition(":")
    if sep and line.isdigit():
        return file, int(line)
    return src or "", None


def _module_stem(source_file: str) -> str:
    """The module stem ``compiler.codegen.emit_monitors`` gives a requirement file."""
    stem = re.sub(r"[^A-Za-z0-9_]", "_", source_file.rsplit("/", 1)[-1].rsplit(".", 1)[0])
    return f"{stem}_monitors" if stem and not stem[0].isdigit() else f"m_{stem}_monitors"


def _class_source(module_text: str, class_name: str) -> str:
    """The text of ``class <class_name>:`` in a generated module, up to the next top-level
    statement."""
    lines = module_text.splitlines()
    out: List[str] = []
    inside = False
    for line in lines:
        if line.startswith(f"class {class_name}:"):
            inside = True
        elif inside and line and not line[0].isspace():
            break
        if inside:
            out.append(line)
    while out and not out[-1].strip():
        out.pop()
    return "\n".join(out)


def marked_fields(text: str, requirement) -> List[Tuple[str, Optional[str]]]:
    """The FRETish text cut into ``(piece, field)`` pieces in order, ``field`` one of
    :data:`FIELD_NAMES` or None for the words between fields ("shall", ...), from the
    :class:`fretish.ast.Requirement` spans (0-based character offsets into ``text``).
    Empty spans (null scope, null condition, null timing) are left out; the pieces always
    join back to ``text``."""
    if requirement is None or getattr(requirement, "freeform", False):
        return [(text, None)]
    spans = []
    cand = [("scope", requirement.scope.span), ("condition", requirement.condition.span),
            ("component", requirement.component_span),
            ("probability", requirement.probability.span if requirement.probability else None),
            ("timing", requirement.timing.span), ("response", requirement.response_span)]
    for name, sp in cand:
        if sp is None or sp.end <= sp.start or sp.end > len(text):
            continue
        spans.append((sp.start, sp.end, name))
    spans.sort()
    out: List[Tuple[str, Optional[str]]] = []
    pos = 0
    for a, b, name in spans:
        if a < pos:  # overlapping spans: keep the first
            continue
        if a > pos:
            out.append((text[pos:a], None))
        out.append((text[a:b], name))
        pos = b
    if pos < len(text):
        out.append((text[pos:], None))
    return out


def _thresholds(requirement) -> list:
    """``var OP constant`` comparisons of the condition and response (timeline dashes)."""
    from fretish import ast as A

    from .timeline import Threshold

    flip = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "=": "=", "!=": "!="}

    def const(e) -> Optional[float]:
        if isinstance(e, A.NumLit):
            return float(e.value)
        if isinstance(e, A.Unary) and e.op == "-" and isinstance(e.operand, A.NumLit):
            return -float(e.operand.value)
        return None

    out = []
    if requirement is None or requirement.freeform:
        return out
    for root in (requirement.condition.expr, requirement.response):
        if root is None:
            continue
        for n in A.walk(root):
            if isinstance(n, A.Binary) and n.op in A.COMPARISON_OPS:
                if isinstance(n.left, A.Var) and const(n.right) is not None:
                    t = Threshold(n.left.name, n.op, const(n.right))
                elif isinstance(n.right, A.Var) and const(n.left) is not None:
                    t = Threshold(n.right.name, flip[n.op], const(n.left))
                else:
                    continue
                if t not in out:
                    out.append(t)
    return out


# --------------------------------------------------------------------------- requirements
@dataclass
class ModuleInfo:
    """A generated monitor module: ``name`` (module stem), ``text``, ``sha256`` of the text,
    ``digest`` (its ``SOURCE_DIGEST``: SHA-256 over the ids and source hashes of its
    monitors)."""

    name: str
    text: str
    sha256: str
    digest: str


@dataclass
class RequirementTrace:
    """What the report shows of one requirement beyond the audit JSON.

    Attributes:
        id, text: as compiled now (``changed`` says how this differs from the audit's).
        file, line: the requirement file and line.
        parent, rationale: from the requirement file (None when absent).
        fields: :func:`marked_fields` pieces.
        key: FRET template key ``scope,condition,timing,satisfaction``.
        ft, ft_inf, pt: the formulas in FRET/SMV syntax (finite trace, infinite trace, past
            time); ft_spot / ft_inf_spot in Spot syntax.
        variables: the FRET variables.
        warnings: of the formalization.
        source_hash: the monitor's ``SOURCE_HASH`` (SHA-256 of id, text, tick period).
        module, class_name, class_source: the generated monitor module stem, class and its
            source text.
        ajpf_label, ajpf_formula: the AJPF property (``label: formula``), or ajpf_reason.
        thresholds: comparisons with constants (timeline dashes).
        error: why it has no formalization or monitor.
        changed: set when the requirement file no longer matches the audit.
    """

    id: str
    text: str = ""
    file: str = ""
    line: Optional[int] = None
    parent: Optional[str] = None
    rationale: Optional[str] = None
    fields: List[Tuple[str, Optional[str]]] = field(default_factory=list)
    key: Optional[str] = None
    ft: Optional[str] = None
    ft_inf: Optional[str] = None
    pt: Optional[str] = None
    ft_spot: Optional[str] = None
    ft_inf_spot: Optional[str] = None
    variables: List[str] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    source_hash: Optional[str] = None
    module: Optional[str] = None
    class_name: Optional[str] = None
    class_source: str = ""
    ajpf_label: Optional[str] = None
    ajpf_formula: Optional[str] = None
    ajpf_reason: Optional[str] = None
    thresholds: list = field(default_factory=list)
    error: Optional[str] = None
    changed: Optional[str] = None


def _trace_of(rp, compiled, psl_mapping: dict, modules: Dict[str, ModuleInfo]
              ) -> RequirementTrace:
    """A :class:`RequirementTrace` from a :class:`monitors.audit.RequirementPlan`."""
    from compiler.ajpf import psl_label_and_formula

    e = compiled.entry
    rt = RequirementTrace(id=rp.id, text=e.text, file=e.source, line=e.line, parent=e.parent,
                          rationale=e.rationale)
    rt.fields = marked_fields(e.text, e.requirement)
    rt.error = rp.error
    rt.thresholds = _thresholds(e.requirement)
    f = compiled.formalization
    if f is not None:
        rt.key, rt.variables, rt.warnings = f.key, list(f.variables), list(f.warnings)
        rt.ft, rt.ft_inf, rt.pt = compiled.smv("ft"), compiled.smv("ft_inf"), compiled.smv("pt")
        rt.ft_spot, rt.ft_inf_spot = compiled.spot("ft"), compiled.spot("ft_inf")
        rt.source_hash = compiled.source_hash
        label, formula = psl_label_and_formula(compiled, psl_mapping)
        if label is None:
            rt.ajpf_reason = formula
        else:
            rt.ajpf_label, rt.ajpf_formula = label, formula
    elif e.requirement is not None:
        rt.key = e.requirement.key
        rt.ajpf_reason = "not formalized"
    if rp.monitor_cls is not None:
        rt.class_name = rp.monitor_cls.__name__
        stem = _module_stem(e.source)
        mod = modules.get(stem)
        if mod is not None and f"\nclass {rt.class_name}:" in mod.text:
            rt.module = stem
            rt.class_source = _class_source(mod.text, rt.class_name)
    return rt


def _modules_of(plan) -> Dict[str, ModuleInfo]:
    out = {}
    for name, text in sorted(plan.modules.items()):
        m = re.search(r"^SOURCE_DIGEST = '([0-9a-f]+)'", text, re.M)
        out[name] = ModuleInfo(name, text, hashlib.sha256(text.encode("utf-8")).hexdigest(),
                               m.group(1) if m else "")
    return out


def trace_requirements(doc: dict, *, plan=None, base: Optional[Path] = None,
                       json_dir: Optional[Path] = None, psl_map: Optional[str] = None
                       ) -> Tuple[Dict[int, RequirementTrace], Dict[str, ModuleInfo], List[str]]:
    """Compile the requirements an audit document names, for what the JSON does not carry.

    Args:
        doc: the audit document (``fretc-audit/1``).
        plan: the :class:`monitors.audit.AuditPlan` the audit ran (``fretc report`` with
            logs); None to rebuild it from the files ``doc`` names (``--from-json``).
        base, json_dir: where relative paths of ``doc`` are looked up (in this order;
            default the current folder).
        psl_map: a ``--psl-map`` TOML file for the AJPF properties.

    Returns:
        ``({index in doc["requirements"]: RequirementTrace}, {module stem: ModuleInfo},
        notes)``; requirements that could not be traced are missing from the first and
        explained in ``notes``.

    Raises:
        ReportError: the ``psl_map`` file cannot be read.
    """
    from compiler.ajpf import AjpfError, load_mapping

    notes: List[str] = []
    try:
        mapping = load_mapping(psl_map)
    except AjpfError as exc:
        raise ReportError(str(exc)) from None
    reqs = doc.get("requirements") or []
    if plan is None:
        plan = _rebuild_plan(doc, base, json_dir, notes)
    if plan is None:
        return {}, {}, notes
    modules = _modules_of(plan)
    by_key = {(rp.id, rp.source): rp for rp in plan.requirements}
    by_id: Dict[str, list] = {}
    for rp in plan.requirements:
        by_id.setdefault(rp.id, []).append(rp)
    out: Dict[int, RequirementTrace] = {}
    for i, r in enumerate(reqs):
        rp = by_key.get((r.get("id"), r.get("source")))
        if rp is None and len(by_id.get(r.get("id"), [])) == 1:
            rp = by_id[r["id"]][0]
        if rp is None or rp.compiled is None:
            notes.append(f"{r.get('id')} ({r.get('source')}): not found in the requirement "
                         "files now: shown from the audit JSON only")
            continue
        rt = _trace_of(rp, rp.compiled, mapping, modules)
        if rp.text != r.get("text"):
            rt.changed = ("the requirement file changed since the audit: the audited text was "
                          f"\u201c{r.get('text')}\u201d; formulas and monitor shown are of "
                          "the current text")
        elif r.get("key") is not None and rt.key != r.get("key"):
            rt.changed = (f"the template key differs from the audited one ({r.get('key')})")
        out[i] = rt
    return out, modules, notes


def _resolve(p: str, base: Optional[Path], json_dir: Optional[Path]) -> Optional[Path]:
    path = Path(p)
    if path.is_absolute():
        return path if path.exists() else None
    for root in [base or Path.cwd()] + ([json_dir] if json_dir is not None else []):
        cand = root / path
        if cand.exists():
            return cand
    return None


def _rebuild_plan(doc: dict, base, json_dir, notes: List[str]):
    from .audit import AuditConfig, AuditInputError, load_plan

    files: List[str] = []
    for r in doc.get("requirements") or []:
        f, _ = _split_source(r.get("source", ""))
        if f and f not in files:
            files.append(f)
    found, missing = [], []
    for f in files:
        p = _resolve(f, base, json_dir)
        (found if p is not None else missing).append(str(p) if p is not None else f)
    for f in missing:
        notes.append(f"requirement file {f} not found: its requirements are shown from the "
                     "audit JSON only")
    if not found:
        return None
    b = doc.get("bindings") or {}
    bfiles = [_resolve(s, base, json_dir) for s in b.get("sources") or []]
    bindings = tuple(str(p) for p in bfiles if p is not None) if all(bfiles) else None
    if bindings is None and b.get("sources"):
        notes.append("binding files of the audit not found: requirements compiled with their "
                     "declared tick periods")
        bindings = ()
    try:
        plan = load_plan(AuditConfig(requirements=tuple(found), bindings=bindings))
    except AuditInputError as exc:
        notes.append(f"cannot compile the requirement files: {exc}")
        return None
    # load_plan reads relative paths as given; map them back to the audit's spelling
    rename = {str(_resolve(f, base, json_dir)): f for f in files
              if _resolve(f, base, json_dir) is not None}
    for rp in plan.requirements:
        file, line = _split_source(rp.source)
        if file in rename:
            rp.source = f"{rename[file]}:{line}"
            if rp.compiled is not None:
                rp.compiled.entry.source = rename[file]
    return plan


# --------------------------------------------------------------------------- the context
def load_audit_json(path: str) -> dict:
    """Read an audit document. Raises :class:`ReportError` when it cannot be read, is not
    JSON, or is not schema ``fretc-audit/1``."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise ReportError(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ReportError(f"{path}: not JSON: {exc}") from None
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        raise ReportError(f"{path}: not a fretc audit document (schema {SCHEMA!r} expected, "
                          f"got {doc.get('schema') if isinstance(doc, dict) else None!r})")
    return doc


def _tick_text(tick: Optional[dict]) -> str:
    if not tick:
        return "-"
    if tick.get("period_ns"):
        return f"every {tick['period_ns'] / 1e6:g} ms (sample-and-hold)"
    if tick.get("topic"):
        return f"one per {tick['topic']} message"
    return "-"


def _generated_line(when: Optional[_dt.datetime] = None) -> str:
    if when is None:
        epoch = os.environ.get("SOURCE_DATE_EPOCH")
        if epoch and epoch.strip().isdigit():
            when = _dt.datetime.fromtimestamp(int(epoch), tz=_dt.timezone.utc)
        else:
            when = _dt.datetime.now(tz=_dt.timezone.utc)
    return GENERATED_PREFIX + when.astimezone(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")


def _version() -> str:
    try:
        from importlib.metadata import version
        return version("fretc")
    except Exception:  # noqa: BLE001 - not installed
        return "dev"


def _witness(v: dict) -> List[Tuple[str, str]]:
    """(label, text) facts of a verdict's witness."""
    out: List[Tuple[str, str]] = []
    fv = v.get("first_violation")
    if fv:
        tick_s = fv.get("tick_time_s", fv.get("log_time_s"))
        base = fv.get("tick_time_base") or "log"
        out.append(("first violation", f"tick {fv['tick']} at {_fmt_s(tick_s)} on the {base} "
                                        f"clock (deciding message log time "
                                        f"{fv['log_time_ns']} ns)"))
        t = fv.get("trigger")
        if t:
            out.append(("trigger", f"tick {t['tick']} at {_fmt_s(t.get('time_s'))} "
                                   f"(log time {t['time_ns']} ns)"))
        sc = fv.get("scope_interval")
        if sc:
            out.append(("scope interval", f"ticks [{sc['start']['tick']}, {sc['end']['tick']}]"
                        f" = {_fmt_s(sc['start'].get('time_s'))} .. "
                        f"{_fmt_s(sc['end'].get('time_s'))}"))
        w = fv.get("window")
        if w:
            hi = _fmt_s(w.get("end_time_s")) if w.get("end_time_s") is not None else "past the end"
            out.append(("response window", f"ticks [{w['start_tick']}, {w['end_tick']}] = "
                        f"{_fmt_s(w.get('start_time_s'))} .. {hi}"))
        if fv.get("obligation"):
            out.append(("obligation", fv["obligation"]))
        if fv.get("reason"):
            out.append(("reason", fv["reason"]))
    l3 = v.get("ltl3") or {}
    if l3.get("status"):
        txt = l3["status"]
        if l3.get("tick") is not None:
            txt += (f" at tick {l3['tick']} ({_fmt_s(l3.get('time_s'))}, "
                    f"log time {l3['time_ns']} ns)")
        out.append(("LTL3 (ft_inf)", txt))
    if v.get("triggers") is not None:
        out.append(("triggers", f"{v['triggers']} in {v.get('intervals')} scope interval(s), "
                                f"{v.get('violations')} failed"))
    listed = v.get("violation_list") or []
    if len(listed) > 1:
        shown = ", ".join(f"{_fmt_s(x['violation']['time_s'])} (#{x['violation']['tick']})"
                          for x in listed[:20])
        more = len(listed) - 20
        total = v.get("violations") or len(listed)
        out.append(("violations at", shown + (f", ... ({more} more listed)" if more > 0 else "")
                    + (f"; {total} in all" if total > len(listed[:20]) else "")))
    out.append(("ticks", f"{v.get('ticks_evaluated')} evaluated"
                         + (f", {v['warmup_ticks']} warm-up" if v.get("warmup_ticks") else "")
                         + (f" ({v['engine']} engine)" if v.get("engine") else "")))
    for n in v.get("notes") or []:
        out.append(("note", n))
    if v.get("error"):
        out.append(("error", v["error"]))
    return out


def _verdict_for(la: dict, i: int, r: dict) -> Optional[dict]:
    """The verdict of requirement ``r`` (index ``i`` of ``requirements``) on log ``la``:
    verdicts are in requirement order; matched by id (and source when ids repeat)."""
    vs = la.get("verdicts") or []
    if i < len(vs) and vs[i].get("requirement") == r.get("id"):
        return vs[i]
    same = [x for x in vs if x.get("requirement") == r.get("id")]
    if len(same) > 1:
        same = [x for x in same if x.get("source") == r.get("source")]
    return same[0] if len(same) == 1 else None


def _damage_text(la: dict) -> str:
    """Where and how a partial log is damaged, and how far it was judged
    (:func:`monitors.audit_output.damage_summary` on the JSON document)."""
    from types import SimpleNamespace

    from .audit_output import damage_summary

    fields = ("start_time_ns", "damage_time_ns", "ticks_after_damage", "damage_cut")
    ns = SimpleNamespace(problems=la.get("problems") or [],
                         problem_counts=la.get("problem_counts") or {},
                         **{k: la.get(k) for k in fields})
    return damage_summary(ns)


def _cell_label(v: Optional[dict]) -> Tuple[str, str]:
    """(verdict class, short text) of a matrix cell."""
    if v is None:
        return "none", "not audited"
    verdict = v.get("verdict", "error")
    text = VERDICT_WORDS.get(verdict, verdict)
    fv = v.get("first_violation")
    if verdict == "violated" and fv and fv.get("tick_time_s", fv.get("log_time_s")) is not None:
        text += f" @ {fv.get('tick_time_s', fv.get('log_time_s')):.3f} s"
    return verdict, text


def _values_table(v: dict, start_ns: Optional[int]) -> dict:
    """Columns and rows of a violation's sampled values (tick, time, variables, held
    message time of each topic) with the ticks of the witness marked."""
    values = v.get("values") or {}
    sources = v.get("sources") or {}
    ticks: Dict[int, dict] = {}
    for name, rows in values.items():
        for r in rows:
            row = ticks.setdefault(r["tick"], {"tick": r["tick"], "time_s": r.get("time_s"),
                                               "time_ns": r.get("time_ns"), "cells": {}})
            row["cells"][name] = r.get("value")
    for topic, rows in sources.items():
        for r in rows:
            row = ticks.setdefault(r["tick"], {"tick": r["tick"], "time_s": r.get("time_s"),
                                               "time_ns": r.get("time_ns"), "cells": {}})
            lt = r.get("message_log_time_ns")
            row["cells"]["@" + topic] = lt
    fv = v.get("first_violation") or {}
    marks: Dict[int, List[str]] = {}
    if fv.get("trigger"):
        marks.setdefault(fv["trigger"]["tick"], []).append("trigger")
    if fv.get("tick") is not None:
        marks.setdefault(fv["tick"], []).append("violation")
    l3 = v.get("ltl3") or {}
    if l3.get("status") in ("violated", "satisfied") and l3.get("tick") is not None:
        marks.setdefault(l3["tick"], []).append(f"LTL3 {l3['status']}")
    w = fv.get("window")
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
                shown = ("-" if raw is None or start_ns is None
                         else f"{(raw - start_ns) / 1e9:.3f} s")
            else:
                shown = _fmt_value(raw)
            cells.append({"raw": json.dumps(raw), "text": shown,
                          "bool": raw if isinstance(raw, bool) else None})
        in_window = bool(w and w["start_tick"] <= k <= w["end_tick"])
        rows.append({"tick": k, "time_s": _fmt_s(row["time_s"]), "time_ns": row["time_ns"],
                     "cells": cells, "marks": ", ".join(marks.get(k, [])),
                     "gap": prev is not None and k != prev + 1, "window": in_window})
        prev = k
    return {"columns": columns, "rows": rows}


def report_context(doc: dict, traces: Dict[int, RequirementTrace],
                   modules: Dict[str, ModuleInfo], *, notes: Sequence[str] = (),
                   annotated: Optional[Dict[int, dict]] = None, title: Optional[str] = None,
                   base: Optional[Path] = None, json_dir: Optional[Path] = None,
                   generated: Optional[str] = None) -> dict:
    """Everything the templates show, as plain dicts and lists (see the templates).

    Args:
        doc: the audit document.
        traces, modules, notes: from :func:`trace_requirements`.
        annotated: log index -> ``{"path": annotated MCAP (relative to the report),
            "events": n, "partial": bool, "damage": str}``.
        title: the report title.
        base, json_dir: where the log, requirement and binding paths are looked up for their
            SHA-256 (in this order; default the current folder).
        generated: the generation line (default :func:`_generated_line`).
    """
    from .timeline import timeline_svg

    anchors = _Anchors()
    reqs = doc.get("requirements") or []
    logs = doc.get("logs") or []
    bindings = doc.get("bindings") or {}
    bvars = bindings.get("variables") or {}
    period_ns = (bindings.get("tick") or {}).get("period_ns")
    def file_info(p: str) -> dict:
        path = _resolve(p, base, json_dir)
        return {"path": p, "sha256": _sha256_file(path) if path is not None and path.is_file()
                else None}

    # runs
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
            "sha256": (file_info(la["log"])["sha256"] if la.get("log") else None),
            "duration": "-" if dur is None else f"{dur:.3f} s",
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

    # requirements and cells
    req_ctx = []
    id_anchor: Dict[str, str] = {}
    for i, r in enumerate(reqs):
        a = anchors.make("req", r.get("id", f"r{i}"))
        id_anchor.setdefault(r.get("id"), a)
        req_ctx.append({"index": i, "anchor": a})
    violations = []
    for i, r in enumerate(reqs):
        rt = traces.get(i)
        rc = req_ctx[i]
        file, line = _split_source(r.get("source", ""))
        parent = rt.parent if rt is not None else None
        variables = []
        for name in (r.get("variables") or (rt.variables if rt else [])):
            b = bvars.get(name)
            variables.append({"name": name, "expr": b["expr"] if b else None,
                              "where": f"{b['source']}:{b['line']}" if b else None,
                              "topics": ", ".join(b.get("topics") or []) if b else ""})
        rc.update({
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
            "changed": rt.changed if rt else "not found in the requirement files: shown from "
                                             "the audit JSON only",
            "cells": [],
        })
        if rt is not None:
            mod = modules.get(rt.module) if rt.module else None
            rc["monitor"] = {"class_name": rt.class_name, "module": rt.module,
                             "module_anchor": f"mod-{_slug(rt.module)}" if rt.module else None,
                             "module_sha256": mod.sha256 if mod else None,
                             "module_digest": mod.digest if mod else None,
                             "source_hash": rt.source_hash, "class_source": rt.class_source,
                             "class_lines": len(rt.class_source.splitlines())}
            rc["ajpf"] = {"label": rt.ajpf_label, "formula": rt.ajpf_formula,
                          "reason": rt.ajpf_reason}
        for j, la in enumerate(logs):
            v = _verdict_for(la, i, r)
            cls, label = _cell_label(v)
            run = runs[j]
            row_anchor = f"{rc['anchor']}-{run['anchor']}"
            word, _, at = label.partition(" @ ")
            cell = {"run": j, "verdict": cls, "label": label, "word": word,
                    "at": ("@ " + at) if at else "",
                    "partial": bool(v and v.get("partial")), "row_anchor": row_anchor,
                    "href": "#" + row_anchor, "witness": _witness(v) if v else [],
                    "violation_anchor": None, "log_time_ns": None}
            if v is not None and cls == "violated" and v.get("first_violation"):
                fv = v["first_violation"]
                va = anchors.make("v", r.get("id", ""), Path(run["name"]).stem)
                cell["violation_anchor"] = va
                cell["href"] = "#" + va
                cell["log_time_ns"] = fv.get("log_time_ns")
                svg = timeline_svg(v, la, period_ns=(la.get("tick") or {}).get("period_ns")
                                   or period_ns,
                                   thresholds=rt.thresholds if rt else (),
                                   title=f"{r.get('id')} violated on {la.get('log')} at "
                                         f"{_fmt_s(fv.get('log_time_s'))}")
                trig = fv.get("trigger") or {}
                l3 = v.get("ltl3") or {}
                violations.append({
                    "anchor": va, "req": rc, "run": run, "svg": svg,
                    "svg_file": f"timelines/{va}.svg", "witness": cell["witness"],
                    "verdict": v, "table": _values_table(v, la.get("start_time_ns")),
                    "violation_ns": fv.get("log_time_ns"),
                    "violation_s": _fmt_s(fv.get("tick_time_s", fv.get("log_time_s"))),
                    "trigger_ns": trig.get("time_ns"), "trigger_s": _fmt_s(trig.get("time_s")),
                    "ltl3_status": l3.get("status"), "ltl3_ns": l3.get("time_ns"),
                    "ltl3_s": _fmt_s(l3.get("time_s")),
                    "partial": bool(v.get("partial")),
                })
            rc["cells"].append(cell)

    # coverage
    never = []
    trig_rows = []
    for rc in req_ctx:
        counts = []
        audited = 0
        fired = False
        unknown = False
        scope_entered = False
        for j, la in enumerate(logs):
            v = _verdict_for(la, rc["index"], reqs[rc["index"]])
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
    # bound topics of the audited requirements' variables; a run misses one when it never
    # had a message on it (missing_topics: in the log but silent) or none was read (the
    # topic is not in the log: those requirements are "error" there)
    used_vars = {n for r in reqs for n in (r.get("variables") or [])}
    bound: Dict[str, List[str]] = {}
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
    coverage = {"never_triggered": never, "triggers": trig_rows, "missing": missing,
                "silent_topics": never_in_any,
                "partial": [r for r in runs if r["partial"]],
                "log_errors": [r for r in runs if r["error"]],
                "errors": [(rc, c) for rc in req_ctx for c in rc["cells"]
                           if c["verdict"] == "error"],
                "warmup": [r for r in runs if r["warmup"]]}

    req_files = []
    for rc in req_ctx:
        if rc["file"] and rc["file"] not in [f["path"] for f in req_files]:
            req_files.append(file_info(rc["file"]))
    bind_files = [file_info(s) for s in bindings.get("sources") or []]
    summary = doc.get("summary") or {}
    ctx = {
        "title": title or "fretc traceability report",
        "generated": generated or _generated_line(),
        "version": _version(), "schema": doc.get("schema"),
        "summary": summary,
        "exit_meaning": {0: "every verdict satisfied or vacuous", 1: "a requirement is violated",
                         2: "something could not be audited",
                         3: "no violation, but a log is partial or had data problems, or a verdict is unknown"
                         }.get(summary.get("exit_code"), ""),
        "requirement_files": req_files, "binding_files": bind_files,
        "tick": _tick_text(bindings.get("tick")), "time_base": bindings.get("time_base") or "-",
        "runs": runs, "requirements": req_ctx, "violations": violations,
        "coverage": coverage, "modules": [
            {"name": m.name, "sha256": m.sha256, "digest": m.digest, "text": m.text,
             "anchor": f"mod-{_slug(m.name)}", "lines": len(m.text.splitlines())}
            for m in modules.values()],
        "notes": list(notes), "field_names": FIELD_NAMES,
        "colors": __import__("monitors.timeline", fromlist=["COLORS"]).COLORS,
    }
    return ctx


# --------------------------------------------------------------------------- rendering
def _env(autoescape: bool):
    import jinja2

    import markupsafe

    from fretish.textsafe import md_code, visible

    def finalize(value: Any) -> Any:
        # every value printed by a template: control and bidi characters shown escaped
        # (XML 1.0 forbids C0 characters; a U+202E must not reorder the page), except
        # markup built here (the inlined SVG, already safe)
        if isinstance(value, str) and not isinstance(value, markupsafe.Markup):
            return visible(value, keep="\n\t")
        return value

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("templates", ""), autoescape=autoescape,
        keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
        undefined=jinja2.StrictUndefined, finalize=finalize)

    def md(text: Any) -> str:
        """Markdown table-cell / inline text: pipes, backticks, newlines and HTML made
        harmless."""
        s = visible("" if text is None else str(text).replace("\n", " "))
        s = s.replace("\\", "\\\\").replace("|", "\\|")
        s = s.replace("<", "&lt;").replace(">", "&gt;").replace("*", "\\*")
        s = s.replace("`", "\\`")
        return s

    def code(text: Any) -> str:
        """Inline Markdown code span that no backtick run in the text can close
        (:func:`fretish.textsafe.md_code`)."""
        return md_code("" if text is None else str(text).replace("\n", " "))

    env.filters["md"] = md
    env.filters["code"] = code
    return env


def render_html(ctx: dict) -> str:
    """The HTML page (``templates/report.html.j2``), XHTML-well-formed so it also parses as
    XML. Text from the inputs is escaped; the timelines are inlined SVG."""
    import markupsafe

    ctx = dict(ctx)
    ctx["violations"] = [dict(v, svg_markup=markupsafe.Markup(v["svg"]))
                         for v in ctx["violations"]]
    return _env(True).get_template("report.html.j2").render(**ctx)


def render_markdown(ctx: dict) -> str:
    """The Markdown report (``templates/report.md.j2``; GitHub-flavoured tables, anchors as
    ``<a id>``, timelines as links to ``timelines/*.svg``)."""
    return _env(False).get_template("report.md.j2").render(**ctx)


@dataclass
class ReportFiles:
    """What :func:`write_report` wrote: the paths, and the annotation results."""

    html: Path
    markdown: Path
    audit_json: Path
    timelines: List[Path]
    annotated: List[Any] = field(default_factory=list)
    notes: List[str] = field(default_factory=list)


def _annotate_all(doc: dict, annotate_dir: Path, base: Optional[Path], json_dir, out_dir: Path,
                  notes: List[str]) -> Tuple[Dict[int, dict], list]:
    from .annotate import annotate_mcap

    done: Dict[int, dict] = {}
    results = []
    used: set = set()
    for j, la in enumerate(doc.get("logs") or []):
        src = la.get("log")
        if not src or la.get("error"):
            continue
        p = _resolve(src, base, json_dir)
        if p is None or p.is_dir() or p.suffix.lower() != ".mcap":
            if p is None:
                notes.append(f"--annotate: {src} not found")
            continue
        name = p.name
        k = 2
        while name in used:
            name = f"{p.stem}_{k}{p.suffix}"
            k += 1
        used.add(name)
        dst = annotate_dir / name
        if dst.exists() and dst.resolve() == p.resolve():
            notes.append(f"--annotate: {dst} is the original log; not overwritten")
            continue
        try:
            res = annotate_mcap(str(p), str(dst), la)
        except (OSError, ValueError) as exc:
            notes.append(f"--annotate: {src}: {exc}")
            continue
        results.append(res)
        done[j] = {"path": os.path.relpath(dst, out_dir).replace(os.sep, "/"),
                   "events": res.events, "partial": res.partial, "damage": res.damage,
                   "compression": res.compression}
    return done, results


def write_report(doc: dict, out_dir: str, *, plan=None, base: Optional[str] = None,
                 json_dir: Optional[str] = None, psl_map: Optional[str] = None,
                 annotate_dir: Optional[str] = None, title: Optional[str] = None,
                 generated: Optional[str] = None) -> ReportFiles:
    """Write the report of an audit document into ``out_dir`` (created).

    Args:
        doc: the audit document (``fretc-audit/1``).
        out_dir: the report folder: ``report.html``, ``report.md``, ``audit.json``,
            ``timelines/*.svg``.
        plan: the audit's :class:`~monitors.audit.AuditPlan` when it ran in this process.
        base, json_dir: where the document's relative paths are looked up.
        psl_map: AJPF mapping TOML (``--psl-map``).
        annotate_dir: also write annotated MCAP copies there (:mod:`monitors.annotate`).
        title: report title.
        generated: the generation line (default: now, or ``SOURCE_DATE_EPOCH``).

    Raises:
        ReportError: the output cannot be written, or the psl map is bad.
    """
    out = Path(out_dir)
    basep = Path(base) if base else None
    jd = Path(json_dir) if json_dir else None
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / "timelines").mkdir(exist_ok=True)
    except OSError as exc:
        raise ReportError(f"{out_dir}: cannot create: {exc}") from None
    traces, modules, notes = trace_requirements(doc, plan=plan, base=basep, json_dir=jd,
                                                psl_map=psl_map)
    annotated: Dict[int, dict] = {}
    results: list = []
    if annotate_dir:
        annotated, results = _annotate_all(doc, Path(annotate_dir), basep, jd, out, notes)
    ctx = report_context(doc, traces, modules, notes=notes, annotated=annotated, title=title,
                         base=basep, json_dir=jd, generated=generated)
    html, md = render_html(ctx), render_markdown(ctx)
    files = ReportFiles(out / "report.html", out / "report.md", out / "audit.json", [],
                        results, notes)
    try:
        for old in sorted((out / "timelines").glob("*.svg")):
            old.unlink()
        for v in ctx["violations"]:
            p = out / v["svg_file"]
            p.write_text(v["svg"], encoding="utf-8")
            files.timelines.append(p)
        files.html.write_text(html, encoding="utf-8")
        files.markdown.write_text(md, encoding="utf-8")
        files.audit_json.write_text(json.dumps(doc, indent=2, sort_keys=True) + "\n",
                                    encoding="utf-8")
    except OSError as exc:
        raise ReportError(f"{out_dir}: cannot write: {exc}") from None
    return files
