"""``fretc qualify -o DIR`` without its command line: the output folder checked and made,
the validation suite run (:func:`fretc.qualification.suite.validate`), the report written
(:mod:`fretc.qualification.report`) and the lines that tell the user the result.
"""

from __future__ import annotations

import importlib.resources
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fretc.common.outputs import OutputError, output_folder, same_path
from fretc.qualification.environment import environment
from fretc.qualification.faults import FAULTS
from fretc.qualification.report import document, write_report
from fretc.qualification.suite import SEED_VARIABLE, Outcome, validate


@dataclass
class Qualified:
    """A finished ``fretc qualify``: the suite's ``outcome``, the report ``doc`` and the
    ``paths`` written."""

    outcome: Outcome
    doc: dict[str, Any]
    paths: list[Path]


def _inside(path: Path, folder: Path) -> bool:
    """``path`` (resolved) is ``folder`` (resolved) or inside it."""
    p, f = path.resolve(), folder.resolve()
    return p == f or f in p.parents


def prepare_folder(path: str) -> Path:
    """The report's folder: new or empty, made when missing, and not inside the installed
    fretc (whose files are the suite's inputs). Returns it as a :class:`Path`.

    Raises:
        OutputError: a file stands there, a folder with files in it, a folder inside the
            installed package, or one that cannot be made (the message names it)."""
    target = Path(path)
    package = Path(str(importlib.resources.files("fretc")))
    # the package's folders as installed: an editable install links its sub-packages
    # from elsewhere (src/fretc/audit -> ../../audit)
    roots = [package] + [p for p in package.iterdir() if p.is_dir()]
    if any(_inside(target, root) for root in roots) or same_path(target, package.parent):
        raise OutputError(f"{path}: inside the installed fretc ({package}), whose files the "
                          "validation suite reads: choose a folder of your own")
    if target.exists() and not target.is_dir():
        raise OutputError(f"{path}: not a folder (fretc qualify writes report.json, "
                          "report.html and its work files into a folder of their own)")
    if target.is_dir() and any(os.scandir(target)):
        raise OutputError(f"{path}: the folder is not empty (fretc qualify needs a new or "
                          "empty folder, so that the report holds only this run's files)")
    return Path(output_folder(target))


def seeded_fault() -> str | None:
    """The fault ``FRETC_QUALIFY_SEED_FAULT`` names (None when unset or empty).

    Raises:
        OutputError: not a name of :data:`fretc.qualification.faults.FAULTS` (the message
            lists them)."""
    name = os.environ.get(SEED_VARIABLE, "").strip()
    if not name:
        return None
    if name not in FAULTS:
        raise OutputError(f"{SEED_VARIABLE}={name!r} is no fault of the suite "
                          f"(one of {', '.join(sorted(FAULTS))})")
    return name


def read_manifest(path: str) -> dict[str, Any]:
    """The installed files against the release manifest at ``path``
    (:func:`fretc.qualification.manifest.compare`, with ``file``: the path).

    Raises:
        OutputError: the file cannot be read or is no manifest (the message names it)."""
    import json

    from fretc.qualification.manifest import compare

    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
        return {"file": path, **compare(doc)}
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise OutputError(f"--manifest {path}: {exc}") from None


def qualify(path: str, command: Any, mutation: bool = True,
            manifest: str | None = None) -> Qualified:
    """Run the validation suite (its end-to-end checks running ``command``, the ``fretc``
    click group) and write its report into the folder ``path`` (:func:`prepare_folder`;
    the checks' files in its ``work`` folder); with ``manifest`` (a release's manifest
    file) the installed files compared with it (:func:`read_manifest`).

    Raises:
        OutputError: the folder is refused (:func:`prepare_folder`), the fault seeded is
            unknown (:func:`seeded_fault`) or the manifest unreadable, before anything is
            written; or the report cannot be written."""
    seeded = seeded_fault()
    compared = read_manifest(manifest) if manifest is not None else None
    folder = prepare_folder(path)
    from fretc.common.outputs import sub_folder

    work = Path(sub_folder(folder, "work"))
    outcome = validate(work, command, seeded=seeded, mutation=mutation)
    doc = document(outcome, environment(), manifest=compared)
    return Qualified(outcome, doc, write_report(folder, doc))


def summary_lines(q: Qualified) -> tuple[list[str], list[str]]:
    """(lines for standard output, lines for standard error) telling the result: the
    counts of requirements passed, failed and not checked here, the mutants detected, the
    report's paths; each failed requirement with its failures and each fault the suite did
    not detect go to standard error."""
    reqs = q.doc["requirements"]
    count = {k: sum(r["result"] == k for r in reqs)
             for k in ("passed", "failed", "partly checked here", "not checked here",
                       "not verified")}
    killed = sum(m["killed"] for m in q.doc["mutants"])
    fretc_doc = q.doc["environment"]["fretc"]
    out = [f"fretc qualify: fretc {fretc_doc['version']}"
           + (f" (commit {fretc_doc['commit']}" + (
               f", modified: {len(fretc_doc['modified'])} file(s) differ from it"
               if fretc_doc.get("modified") else "") + ")" if fretc_doc["commit"] else ""),
           f"{len(q.outcome.checks)} checks, "
           f"{sum(c.passed and c.ran for c in q.outcome.checks)} passed"
           + "".join(f", {c.check.name} skipped ({c.skipped})" for c in q.outcome.checks
                     if not c.ran) + "; "
           f"requirements: {count['passed']} passed, {count['failed']} failed, "
           + (f"{count['partly checked here']} partly checked here (a check of theirs "
              "skipped), " if count["partly checked here"] else "") +
           f"{count['not checked here']} not checked here (shown by the project's tests), "
           f"{count['not verified']} not verified (the requirements page says why)",
           f"mutation run: {killed} of {len(q.doc['mutants'])} seeded faults detected"
           if q.doc["mutants"] else "mutation run: not run (--no-mutation)"]
    out += [f"report: {p}" for p in q.paths]
    err = []
    for r in reqs:
        if r["result"] == "failed":
            err.append(f"FAILED {r['id']}: {r['statement']}")
            err += [f"  {f}" for f in r["failures"]]
    err += [f"NOT DETECTED: seeded fault {m['fault']} ({m['what']})"
            for m in q.doc["mutants"] if not m["killed"]]
    m = q.doc.get("manifest")
    if m is not None:
        counts = {k: len(m[k]) for k in ("changed", "missing", "extra")}
        if any(counts.values()):
            err.append(f"NOT THE RELEASE: the installed files differ from {m['file']} "
                       f"(version {m['version']}): " + ", ".join(
                           f"{n} {k}" for k, n in counts.items() if n)
                       + "; " + ", ".join((m["changed"] + m["missing"] + m["extra"])[:5]))
        else:
            out.insert(1, f"manifest: the installed files are those of {m['file']} "
                          f"(version {m['version']})")
    if q.outcome.seeded:
        err.insert(0, f"{SEED_VARIABLE}={q.outcome.seeded}: the fault was seeded for this run")
    return out, err
