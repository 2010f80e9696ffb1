"""What ``fretc export`` writes back into a requirements tool: one result per requirement of
an audit document (``fretc audit --json``), and the atomic writes every exporter uses.

A requirement's result over all the runs of the audit (:func:`requirement_results`):

Design notes: ARCHITECTURE.md, `reports/export_results.py`."""

from __future__ import annotations

import dataclasses
import datetime as _dt
import hashlib
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass

from fretc.common.outputs import write_file
from fretc.reports.rollup import rollups

__all__ = ["RequirementResult", "requirement_results", "audit_identity", "write_atomic",
           "replace_tree", "VERDICT_ORDER", "NOT_FORMALIZED"]

NOT_FORMALIZED = "not formalized"
#: The verdict a requirement gets over several runs: the first of these any run has.
VERDICT_ORDER = ("error", "violated", "unknown", "satisfied", "vacuous")


@dataclass(frozen=True)
class RequirementResult:
    """One requirement's result (module docstring). ``tool_id`` is its origin's identifier
    (None for a ``.fret`` requirement); ``runs`` the number of runs that judged it."""

    id: str
    tool_id: str | None
    verdict: str
    evidence: str
    ft: str | None
    pt: str | None
    audit_id: str
    audit_date: str
    runs: int
    rollup: str | None = None
    rollup_path: str | None = None


def audit_identity(path: str, raw: bytes, date: str | None = None) -> tuple[str, str]:
    """(audit id, audit date) of the audit document at ``path`` with bytes ``raw``
    (module docstring). ``date`` wins when given."""
    digest = "sha256:" + hashlib.sha256(raw).hexdigest()[:16]
    if date:
        return digest, date
    stamp = _dt.datetime.fromtimestamp(int(os.stat(path).st_mtime), _dt.UTC)
    return digest, stamp.strftime("%Y-%m-%dT%H:%M:%SZ")


def _evidence(rows: list[tuple[str, dict]]) -> str:
    """The evidence line of one requirement: counts per verdict, then the first violation
    of each violating run."""
    counts: dict[str | None, int] = {}
    for _log, v in rows:
        counts[v.get("verdict")] = counts.get(v.get("verdict"), 0) + 1
    parts = [f"{k} on {counts[k]} of {len(rows)} runs" for k in VERDICT_ORDER if k in counts]
    for log, v in rows:
        fv = v.get("first_violation")
        if v.get("verdict") == "violated" and fv:
            when = fv.get("tick_time_s")
            parts.append(f"{log}: first missed at tick {fv.get('tick')}"
                         + (f" ({when:g} s)" if isinstance(when, (int, float)) else "")
                         + (f": {fv.get('reason')}" if fv.get("reason") else ""))
        elif v.get("verdict") == "error" and v.get("error"):
            parts.append(f"{log}: {str(v['error']).splitlines()[0]}")
    return "; ".join(parts) if parts else "no run judged it"


def requirement_results(doc: dict, audit_id: str, audit_date: str
                        ) -> dict[str, RequirementResult]:
    """Requirement id -> :class:`RequirementResult` of the audit document ``doc`` (the
    audited requirements, then its ``not_formalized`` items), in the document's order."""
    per: dict[str, list[tuple[str, dict]]] = {}
    for la in doc.get("logs") or []:
        for v in la.get("verdicts") or []:
            per.setdefault(v.get("requirement"), []).append((la.get("log"), v))
    out: dict[str, RequirementResult] = {}
    for r in doc.get("requirements") or []:
        rows = per.get(r["id"], [])
        verdicts = {v.get("verdict") for _l, v in rows}
        verdict = next((k for k in VERDICT_ORDER if k in verdicts),
                       "error" if r.get("error") else "unknown")
        origin = r.get("origin") or {}
        out[r["id"]] = RequirementResult(
            r["id"], origin.get("tool_id"), verdict,
            _evidence(rows) if rows else (r.get("error") or "no run judged it"),
            r.get("ft"), r.get("pt"), audit_id, audit_date, len(rows))
    for item in doc.get("not_formalized") or []:
        origin = item.get("origin") or {}
        out.setdefault(item["id"], RequirementResult(
            item["id"], origin.get("tool_id"), NOT_FORMALIZED,
            "no FRETish text: not audited", None, None, audit_id, audit_date, 0))
    for rid, ru in rollups(doc, {k: r.verdict for k, r in out.items()}).items():
        if rid in out:
            out[rid] = dataclasses.replace(out[rid], rollup=ru.verdict, rollup_path=ru.text())
    return out


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_atomic(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder renamed over
    it (:func:`fretc.common.outputs.write_file`): a reader (or a failure half-way) never sees
    a part of the file, and a link at ``path`` is replaced, never written through. Raises
    :class:`fretc.common.outputs.OutputError` (an OSError) when it cannot be written."""
    write_file(path, data)


def replace_tree(build: Callable[[str], object], out: str) -> None:
    """Build a folder with ``build(tmp_folder)`` beside ``out`` and rename it to ``out``
    (which must not exist, or be an empty folder); on any error the temporary folder is
    removed and ``out`` is untouched. Raises :class:`FileExistsError` for a non-empty
    ``out``."""
    if os.path.isdir(out) and os.listdir(out):
        raise FileExistsError(f"{out}: the output folder exists and is not empty")
    parent = os.path.dirname(os.path.abspath(out))
    tmp = tempfile.mkdtemp(dir=parent, prefix=".fretc-export-")
    os.chmod(tmp, 0o777 & ~_umask())  # as mkdir would make it (mkdtemp makes 0700)
    try:
        build(tmp)
        if os.path.isdir(out):
            os.rmdir(out)
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
