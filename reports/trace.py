"""Requirement traceability for the report (``fretc report``): what the report shows of each
requirement beyond the audit JSON (parent, rationale, the FRETish fields marked in its text,
ft / ft_inf / pt, the generated monitor class and module, the AJPF property), obtained by
compiling the requirement files the audit document names, exactly as ``fretc audit`` does
(:func:`fretc.audit.load_plan`).
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.compiler.ajpf import AjpfError, load_mapping, psl_label_and_formula
from fretc.compiler.codegen import file_stems
from fretc.fretish import ast as A
from fretc.common.errors import FretcError

from fretc.audit import AuditConfig, AuditInputError, load_plan
from fretc.reports.timeline import Threshold

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["ReportError", "FIELD_NAMES", "ModuleInfo", "RequirementTrace", "marked_fields",
           "thresholds", "trace_requirements", "resolve_input", "split_source"]

#: The FRETish fields marked in the requirement text, in sentence order.
FIELD_NAMES = ("scope", "condition", "component", "probability", "timing", "response")


class ReportError(FretcError):
    """The report cannot be made: unreadable or wrong-schema JSON, unwritable output."""


def split_source(src: str) -> tuple[str, int | None]:
    """``"file:line"`` -> (file, line); (``src``, None) when it ends in no line number."""
    file, sep, line = (src or "").rpartition(":")
    if sep and line.isdigit():
        return file, int(line)
    return src or "", None


def resolve_input(p: str, base: Path | None, json_dir: Path | None) -> Path | None:
    """An input path of the audit document as it exists here: absolute as is, relative
    looked up under ``base`` (default the current folder), then ``json_dir``; None when
    absent."""
    path = Path(p)
    if path.is_absolute():
        return path if path.exists() else None
    for root in [base or Path.cwd()] + ([json_dir] if json_dir is not None else []):
        cand = root / path
        if cand.exists():
            return cand
    return None


def _class_source(module_text: str, class_name: str) -> str:
    """The source of one requirement's monitor in a generated module: its
    ``<class_name> = _monitor(...)`` statement followed by the ``_SHAPES`` entry holding its
    step logic (modules of an older layout: its ``class <class_name>:`` statement)."""
    lines = module_text.splitlines()
    out: list[str] = []
    inside = False
    for line in lines:
        if line.startswith((f"class {class_name}:", f"{class_name} = _monitor(")):
            inside = True
        elif inside and line and not line[0].isspace():
            if line == ")":
                out.append(line)
            break
        if inside:
            out.append(line)
    while out and not out[-1].strip():
        out.pop()
    m = re.search(r"# step logic: _SHAPES\[(\d+)\]", "\n".join(out[:2]))
    if m:
        shape: list[str] = []
        for line in lines:
            if line == f"    # shape {m.group(1)}":
                shape.append(f"# _SHAPES[{m.group(1)}]: (KEY, STATUS_NOTE, bad table, good "
                             "table, step logic)")
            elif shape and (line.startswith("    # shape ") or line == ")"):
                break
            elif shape:
                shape.append(line)
        out += [""] + shape
    return "\n".join(out)


def marked_fields(text: str, requirement: A.Requirement) -> list[tuple[str, str | None]]:
    """The FRETish text cut into ``(piece, field)`` pieces in order, ``field`` one of
    :data:`FIELD_NAMES` or None for the words between fields ("shall", ...), from the
    :class:`fretc.fretish.ast.Requirement` spans (0-based character offsets into ``text``).
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
    out: list[tuple[str, str | None]] = []
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


_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "=": "=", "!=": "!="}


def _const(e) -> float | None:
    """A numeric literal (possibly negated) as a float; None for anything else."""
    if isinstance(e, A.NumLit):
        return float(e.value)
    if isinstance(e, A.Unary) and e.op == "-" and isinstance(e.operand, A.NumLit):
        return -float(e.operand.value)
    return None


def thresholds(requirement: A.Requirement) -> list[Threshold]:
    """``var OP constant`` comparisons of the condition and response of a
    :class:`fretc.fretish.ast.Requirement` (the timeline's dashed lines), in tree order without
    repeats; ``constant OP var`` is turned round. None or free-form: none."""
    out: list[Threshold] = []
    if requirement is None or requirement.freeform:
        return out
    for root in (requirement.condition.expr, requirement.response):
        if root is None:
            continue
        for n in A.walk(root):
            if isinstance(n, A.Binary) and n.op in A.COMPARISON_OPS:
                if isinstance(n.left, A.Var) and (c := _const(n.right)) is not None:
                    t = Threshold(n.left.name, n.op, c)
                elif isinstance(n.right, A.Var) and (c := _const(n.left)) is not None:
                    t = Threshold(n.right.name, _FLIP[n.op], c)
                else:
                    continue
                if t not in out:
                    out.append(t)
    return out


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
    line: int | None = None
    parent: str | None = None
    rationale: str | None = None
    fields: list[tuple[str, str | None]] = field(default_factory=list)
    key: str | None = None
    ft: str | None = None
    ft_inf: str | None = None
    pt: str | None = None
    ft_spot: str | None = None
    ft_inf_spot: str | None = None
    variables: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    source_hash: str | None = None
    module: str | None = None
    class_name: str | None = None
    class_source: str = ""
    ajpf_label: str | None = None
    ajpf_formula: str | None = None
    ajpf_reason: str | None = None
    thresholds: list[Threshold] = field(default_factory=list)
    error: str | None = None
    changed: str | None = None
    reading: str | None = None
    diagram_svg: str | None = None
    semantics_svg: str | None = None


def _trace_of(rp, compiled, psl_mapping: dict, modules: dict[str, ModuleInfo]
              ) -> RequirementTrace:
    """A :class:`RequirementTrace` from a :class:`fretc.audit.RequirementPlan`."""
    e = compiled.entry
    rt = RequirementTrace(id=rp.id, text=e.text, file=e.source, line=e.line, parent=e.parent,
                          rationale=e.rationale)
    rt.fields = marked_fields(e.text, e.requirement)
    rt.error = rp.error
    rt.thresholds = thresholds(e.requirement)
    f = compiled.formalization
    if f is not None:
        rt.key, rt.variables, rt.warnings = f.key, list(f.variables), list(f.warnings)
        rt.ft, rt.ft_inf, rt.pt = compiled.smv_text["ft"], compiled.smv_text["ft_inf"], compiled.smv_text["pt"]
        rt.ft_spot, rt.ft_inf_spot = compiled.spot("ft"), compiled.spot("ft_inf")
        rt.source_hash = compiled.source_hash
        _explained(rt, compiled)
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
        # the stem compiler.codegen.emit_monitors gives the file (when no other file of
        # the plan shares its name; the class is looked up in the text to be sure)
        stem = file_stems([e.source], "_monitors")[e.source]
        mod = modules.get(stem)
        if mod is not None and (f"\nclass {rt.class_name}:" in mod.text
                                or f"\n{rt.class_name} = _monitor(" in mod.text):
            rt.module = stem
            rt.class_source = _class_source(mod.text, rt.class_name)
    return rt


def _explained(rt: RequirementTrace, compiled) -> None:
    """The reading and diagram of ``fretc explain`` on the requirement's card, and FRET's
    semantics diagram (:mod:`fretc.reports.semantics_diagram`)."""
    from fretc.monitors.explain import explain

    from fretc.reports.explanation import svg

    try:
        x = explain(compiled)
    except (ValueError, KeyError):  # free-form, or nothing to draw: the card goes without
        return
    rt.reading, rt.diagram_svg = x.reading, svg(x)
    from fretc.reports.semantics_diagram import svg as semantics_svg

    f, req = compiled.formalization, compiled.requirement
    if f is not None and req is not None:
        rt.semantics_svg = semantics_svg(req, f.ticks, rt.id)


def _modules_of(plan) -> dict[str, ModuleInfo]:
    out = {}
    for name, text in sorted(plan.modules.items()):
        m = re.search(r"^SOURCE_DIGEST = '([0-9a-f]+)'", text, re.M)
        out[name] = ModuleInfo(name, text, hashlib.sha256(text.encode("utf-8")).hexdigest(),
                               m.group(1) if m else "")
    return out


def trace_requirements(doc: dict, *, plan: AuditPlan | None = None, base: Path | None = None,
                       json_dir: Path | None = None, psl_map: str | None = None
                       ) -> tuple[dict[int, RequirementTrace], dict[str, ModuleInfo], list[str]]:
    """Compile the requirements an audit document names, for what the JSON does not carry.

    Args:
        doc: the audit document (``fretc-audit/1``).
        plan: the :class:`fretc.audit.AuditPlan` the audit ran (``fretc report`` with
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
    notes: list[str] = []
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
    by_id: dict[str, list] = {}
    for rp in plan.requirements:
        by_id.setdefault(rp.id, []).append(rp)
    out: dict[int, RequirementTrace] = {}
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


def _rebuild_plan(doc: dict, base: Path | None, json_dir: Path | None, notes: list[str]):
    """The :class:`fretc.audit.AuditPlan` of the requirement and binding files ``doc``
    names, found under ``base`` / ``json_dir``, with the sources spelled as in ``doc``; None
    (and a note) when no requirement file is found or they do not compile."""
    files: list[str] = []
    for r in doc.get("requirements") or []:
        f, _ = split_source(r.get("source", ""))
        if f and f not in files:
            files.append(f)
    found: list[Any] = []
    missing: list[Any] = []
    for f in files:
        p = resolve_input(f, base, json_dir)
        (found if p is not None else missing).append(str(p) if p is not None else f)
    for f in missing:
        notes.append(f"requirement file {f} not found: its requirements are shown from the "
                     "audit JSON only")
    if not found:
        return None
    b = doc.get("bindings") or {}
    bfiles = [resolve_input(s, base, json_dir) for s in b.get("sources") or []]
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
    rename = {str(resolve_input(f, base, json_dir)): f for f in files
              if resolve_input(f, base, json_dir) is not None}
    for rp in plan.requirements:
        file, line = split_source(rp.source)
        if file in rename:
            rp.source = f"{rename[file]}:{line}"
            if rp.compiled is not None:
                rp.compiled.entry.source = rename[file]
    return plan
