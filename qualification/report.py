"""The qualification report of ``fretc qualify``: ``report.json`` (the record, for tools)
and ``report.html`` (the same, for a reader), written through :mod:`fretc.common.outputs`.

The JSON document: ``format`` (1), ``tool`` (``fretc qualify``), ``date`` (UTC, ISO 8601:
when the run ended; the one field that differs between two runs of one installation),
``result`` (``passed`` or ``failed``), ``manifest`` (``--manifest``: the installed files
against the release's, else null), ``failed_requirements`` (ids), ``seeded_fault`` (the
fault ``FRETC_QUALIFY_SEED_FAULT`` seeded, or null), ``environment``
(:func:`fretc.qualification.environment.environment`), ``requirements`` (each id with its
result, :meth:`fretc.qualification.suite.Outcome.requirement_results`), ``checks`` (each
check's result) and ``mutants`` (the mutation run: each fault, where, what, killed and by
which check).
"""

from __future__ import annotations

import datetime
import html
import json
from pathlib import Path
from typing import Any

from fretc.qualification.suite import Outcome


def document(outcome: Outcome, environment: dict[str, Any],
             now: datetime.datetime | None = None,
             manifest: dict[str, Any] | None = None) -> dict[str, Any]:
    """The report's JSON document (module docstring) of a validation run; ``now`` its date
    (default: the current UTC time); ``manifest`` the comparison with a release's manifest
    (:func:`fretc.qualification.manifest.compare`, with its ``file``), which fails the run
    when a file differs."""
    when = (now or datetime.datetime.now(datetime.UTC)).replace(microsecond=0)
    differs = manifest is not None and any(manifest[k] for k in ("changed", "missing",
                                                                  "extra"))
    return {
        "format": 1, "tool": "fretc qualify", "date": when.isoformat(),
        "result": "passed" if outcome.passed and not differs else "failed",
        "manifest": manifest,
        "failed_requirements": outcome.failed_requirements,
        "seeded_fault": outcome.seeded, "environment": environment,
        "requirements": outcome.requirement_results(),
        "checks": [c.to_json() for c in outcome.checks],
        "mutants": outcome.mutants,
    }


def _e(value: Any) -> str:
    """A value as HTML text (escaped; None as an en dash)."""
    return "&ndash;" if value is None else html.escape(str(value))


def _table(head: list[str], rows: list[list[Any]]) -> str:
    """An HTML table (every cell escaped)."""
    out = ["<table><tr>" + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{_e(c)}</td>" for c in row) + "</tr>" for row in rows]
    return "\n".join(out + ["</table>"])


def html_page(doc: dict[str, Any]) -> str:
    """The report as one HTML page (no script, no external resource)."""
    env = doc["environment"]
    fretc = env["fretc"]
    parts = [
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>fretc qualification "
        "report</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:"
        "collapse;margin:1em 0}td,th{border:1px solid #999;padding:2px 6px;text-align:left;"
        "vertical-align:top}.failed{color:#b00}</style></head><body>",
        f"<h1>fretc qualification report: {_e(doc['result'])}</h1>",
        _table(["fretc", "commit", "package files (sha256)", "Python", "platform", "date",
                "seeded fault"],
               [[fretc["version"], f"{fretc['commit']}" + (
                   f" (modified: {', '.join(fretc['modified'])})" if fretc.get("modified")
                   else ""), f"{fretc['files_sha256']} "
                 f"({fretc['files']} files)", env["python"]["version"],
                 env["platform"]["platform"], doc["date"], doc["seeded_fault"]]]),
    ]
    m = doc.get("manifest")
    if m is not None:
        bad = [f"{k}: {', '.join(m[k])}" for k in ("changed", "missing", "extra") if m[k]]
        parts.append(f"<p class=\"{'failed' if bad else 'passed'}\">Manifest "
                     f"{_e(m['file'])} (version {_e(m['version'])}): "
                     + (_e("; ".join(bad)) if bad else "the installed files are the release's")
                     + "</p>")
    if doc["failed_requirements"]:
        parts.append("<p class=\"failed\">Failed requirements: "
                     f"{_e(', '.join(doc['failed_requirements']))}</p>")
    parts += ["<h2>Requirements</h2>",
              _table(["id", "result", "checks", "statement", "failures"],
                     [[r["id"], r["result"], ", ".join(r["checks"]) + "".join(
                         f", {name} (skipped)" for name in r.get("skipped", ())),
                       r["statement"],
                       "; ".join(r["failures"])] for r in doc["requirements"]]),
              "<h2>Checks</h2>",
              _table(["check", "result", "requirements", "what", "seconds", "failures"],
                     [[c["name"], c["result"] + (f" ({c['skipped']})" if c["skipped"] else ""),
                       ", ".join(c["requirements"]), c["what"], c["seconds"],
                       "; ".join(c["failures"])] for c in doc["checks"]]),
              "<h2>Mutation run</h2>",
              _table(["fault", "where", "what", "detected", "by"],
                     [[m["fault"], m["where"], m["what"], "yes" if m["killed"] else "NO",
                       ", ".join(m["killed_by"])] for m in doc["mutants"]]),
              "<h2>Installed distributions</h2>",
              _table(["name", "version", "fretc dependency", "sha256", "of"],
                     [[d["name"], d["version"], "yes" if d["required"] else "", d["sha256"],
                       d["hashed"]] for d in env["distributions"]]),
              "</body></html>"]
    return "\n".join(parts) + "\n"


def write_report(folder: Path, doc: dict[str, Any]) -> list[Path]:
    """Write ``report.json`` and ``report.html`` into ``folder`` (which must exist), each
    whole or not at all; returns their paths. Raises
    :class:`fretc.common.outputs.OutputError` when one cannot be written."""
    from fretc.common.outputs import write_file

    paths = [folder / "report.json", folder / "report.html"]
    write_file(paths[0], json.dumps(doc, indent=2, sort_keys=True) + "\n")
    write_file(paths[1], html_page(doc))
    return paths
