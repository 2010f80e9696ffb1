"""The validation suite's end-to-end checks: ``fretc audit`` run as a user runs it (the
installed command, through click in this process), on CSV traces written in the run's work
folder, its exit codes, verdicts and audit JSON compared with what FRET's definitions and
the documentation say (:mod:`fretc.qualification.reference` for the verdicts;
docs/guide/audits.md for exit codes and unknown ticks). The checks on MCAP logs are
:mod:`fretc.qualification.checks_logs`'s.
"""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

from fretc.qualification import reference as ref
from fretc.qualification.checks import SEED, Check, Run

#: CSV traces of the end-to-end differential check
E2E_TRACES = 10


def fretc(run: Run, args: list[str]) -> tuple[int, str]:
    """Run the ``fretc`` command (``run.command``: the click group the console script runs)
    with ``args`` in this process through click's test runner; returns (exit code, its
    output). Raises ``ValueError`` when the run has no command."""
    from click.testing import CliRunner

    if run.command is None:
        raise ValueError("the end-to-end checks need the fretc command (Run.command)")
    result = CliRunner().invoke(run.command, args, catch_exceptions=True)
    text = result.output
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        text += f"\n{type(result.exception).__name__}: {result.exception}"
    return result.exit_code, text


def audit(run: Run, name: str, requirements: str, logs: dict[str, str],
          extra: tuple[str, ...] = ()) -> tuple[int, dict[str, Any] | None, str]:
    """Write ``requirements`` (a .fret text) and the CSV ``logs`` (name -> text) into a
    folder ``name`` of the work folder and audit them with ``--json``: (exit code, the audit
    JSON or None when none was written, the command's output)."""
    folder = run.work / name
    folder.mkdir(parents=True, exist_ok=True)
    req = folder / "requirements.fret"
    req.write_text(requirements, encoding="utf-8")
    paths = []
    for log, text in sorted(logs.items()):
        (folder / log).write_text(text, encoding="utf-8")
        paths.append(str(folder / log))
    out = folder / "audit.json"
    code, text = fretc(run, ["audit", "-r", str(req), *paths, "--json", str(out), "--no-progress",
                        *extra])
    doc = json.loads(out.read_text("utf-8")) if out.exists() else None
    return code, doc, text


def verdicts(doc: dict[str, Any] | None) -> dict[tuple[str, str], dict[str, Any]]:
    """The audit JSON's verdicts by (log file name, requirement id)."""
    if doc is None:
        return {}
    return {(Path(log["log"]).name, v["requirement"]): v
            for log in doc["logs"] for v in log["verdicts"]}


def _csv(columns: dict[str, list[Any]]) -> str:
    """A CSV trace: a header of the column names, one row a tick."""
    names = sorted(columns)
    rows = zip(*(columns[n] for n in names))
    cell = {True: "true", False: "false"}
    return "\n".join([",".join(names)] + [",".join(cell.get(v, str(v)) if isinstance(v, bool)
                                                     else str(v) for v in row)
                                            for row in rows]) + "\n"


def check_audit_keys(run: Run) -> list[str]:
    """The 288 key sentences audited on random CSV traces (one ``fretc audit``): each
    verdict is the reference's, the exit code 1 exactly when one is violated (else 0), and
    the audit JSON is valid under its schema."""
    from fretc.reports.files import schema_problem

    rnd = random.Random(SEED + 1)
    keys = ref.key_sentences()
    text = "".join(f"K{i:03d}: {sentence}\n" for i, (_, sentence) in enumerate(keys))
    trace_list = [ref.random_trace(rnd, rnd.randint(1, ref.DURATION + 7))
                  for _ in range(E2E_TRACES)]
    logs = {f"t{j:02d}.csv": _csv({v: [t[v] for t in tr] for v in ref.VARIABLES})
            for j, tr in enumerate(trace_list)}
    code, doc, output = audit(run, "keys", text, logs)
    got = verdicts(doc)
    out, violated = [], False
    for j, tr in enumerate(trace_list):
        for i, (key, _) in enumerate(keys):
            want = ref.verdict(key, tr)
            violated |= want == "violated"
            have = got.get((f"t{j:02d}.csv", f"K{i:03d}"), {}).get("verdict")
            if have != want:
                out.append(f"{key} on t{j:02d}.csv: {have}, expected {want}")
    if code != (1 if violated else 0):
        out.append(f"exit code {code}, expected {1 if violated else 0}: {output[-300:]}")
    if doc is not None and (problem := schema_problem(doc)) is not None:
        out.append(f"the audit JSON breaks its schema: {problem}")
    return out[:5] + ([f"... and {len(out) - 5} more"] if len(out) > 5 else [])


def check_streamed_csv(run: Run) -> list[str]:
    """The 288 key sentences audited on random CSV traces of up to 40 rows judged as their
    rows are read (the default) and by the judge that holds every tick (the streamed judge
    switched off in this process): the audit JSON is the same bytes."""
    from fretc.audit import streamed

    rnd = random.Random(SEED + 10)
    keys = ref.key_sentences()
    text = "".join(f"K{i:03d}: {sentence}\n" for i, (_, sentence) in enumerate(keys))
    logs = {f"s{j:02d}.csv": _csv({v: [t[v] for t in tr] for v in ref.VARIABLES})
            for j, tr in enumerate(ref.random_trace(rnd, rnd.randint(1, 40))
                                   for _ in range(4))}
    docs = []
    for on in (True, False):
        old = streamed.ENABLED
        streamed.ENABLED = on
        try:
            code, _, output = audit(run, f"streamed-{on}", text, logs)
        finally:
            streamed.ENABLED = old
        path = run.work / f"streamed-{on}" / "audit.json"
        if not path.exists():
            return [f"no audit JSON (streamed {on}, exit {code}): {output.strip()[-200:]}"]
        docs.append(path.read_text("utf-8").replace(f"streamed-{on}", "streamed"))
    if docs[0] != docs[1]:
        return ["the audit JSON of the CSV traces judged as read differs from the whole-trace "
                "judge's"]
    return []


def check_verdicts_and_exit(run: Run) -> list[str]:
    """Satisfied, violated (with its first violation and its robustness), error and a
    syntax error, each with the documented exit code (0, 1, 2, 2)."""
    always = "R1: the sw shall always satisfy x <= 5\n"
    out = []
    code, doc, _ = audit(run, "ok", always, {"ok.csv": _csv({"x": [1, 3, 2]})})
    v = verdicts(doc).get(("ok.csv", "R1"), {})
    if (code, v.get("verdict"), (v.get("robustness") or {}).get("value")) != (0, "satisfied", 2.0):
        out.append(f"satisfied: exit {code}, {v.get('verdict')}, robustness "
                   f"{(v.get('robustness') or {}).get('value')}; expected 0, satisfied, 2.0")
    code, doc, _ = audit(run, "bad", always, {"bad.csv": _csv({"x": [1, 3, 7, 2]})})
    v = verdicts(doc).get(("bad.csv", "R1"), {})
    first = (v.get("first_violation") or {}).get("tick")
    margin = (v.get("robustness") or {}).get("value")
    if (code, v.get("verdict"), first, margin) != (1, "violated", 2, -2.0):
        out.append(f"violated: exit {code}, {v.get('verdict')}, first violation at tick "
                   f"{first}, robustness {margin}; expected 1, violated, 2, -2.0")
    code, doc, _ = audit(run, "error", "R1: the sw shall always satisfy y <= 5\n",
                         {"e.csv": _csv({"x": [1]})})
    v = verdicts(doc).get(("e.csv", "R1"), {})
    if code != 2 or v.get("verdict") != "error" or "y" not in (v.get("error") or ""):
        out.append(f"a variable the log lacks: exit {code}, {v.get('verdict')} "
                   f"({v.get('error')}); expected 2, error naming y")
    code, doc, text = audit(run, "syntax", "R1: the sw shal satisfy r\n",
                            {"s.csv": _csv({"r": [True]})})
    if code != 2 or "requirements.fret:1:" not in text:
        out.append(f"a syntax error: exit {code}, {text.strip()[-200:]!r}; expected 2 and "
                   "requirements.fret:1:col")
    return out


def check_unknown(run: Run) -> list[str]:
    """Three-valued verdicts: an ``unknown`` cell or a NaN compared that could change the
    verdict gives ``unknown`` with its reason (exit 3); a violation in the ticks read stands
    (exit 1); a run cut while an obligation is open is ``unknown`` (exit 3), the log
    partial."""
    always = "R1: the sw shall always satisfy x <= 5\n"
    cases = (("unknown-cell", always, {"x": [1, "unknown", 2]}, 3, "unknown"),
             ("unknown-nan", always, {"x": [1, "nan", 2]}, 3, "unknown"),
             ("unknown-read", always, {"x": [7, "unknown", 2]}, 1, "violated"),
             ("cut", "R1: upon c the sw shall eventually satisfy r\n",
              {"c": [True, False, "cut"], "r": [False, False, "cut"]}, 3, "unknown"))
    out = []
    for name, text, columns, want_code, want in cases:
        code, doc, _ = audit(run, name, text, {f"{name}.csv": _csv(columns)})
        v = verdicts(doc).get((f"{name}.csv", "R1"), {})
        if (code, v.get("verdict")) != (want_code, want):
            out.append(f"{name}: exit {code}, {v.get('verdict')}; expected {want_code}, {want}")
        elif want == "unknown" and not v.get("unknown_reason"):
            out.append(f"{name}: unknown without a reason")
        if name == "cut" and doc is not None and not doc["logs"][0]["partial"]:
            out.append("cut: the log is not partial")
        if name == "unknown-nan" and doc is not None and not any(
                p["kind"] == "nan" for p in doc["logs"][0]["problems"]):
            out.append("unknown-nan: no nan problem listed")
    return out


def check_outputs_over_inputs(run: Run) -> list[str]:
    """An audit told to write its JSON over its own input trace is refused (exit 2, both
    named) before anything is read or written: the trace is left as it was."""
    folder = run.work / "outputs"
    folder.mkdir(parents=True, exist_ok=True)
    req, log = folder / "requirements.fret", folder / "t.csv"
    req.write_text("R1: the sw shall always satisfy x <= 5\n", encoding="utf-8")
    text = _csv({"x": [1, 2]})
    log.write_text(text, encoding="utf-8")
    code, output = fretc(run, ["audit", "-r", str(req), str(log), "--json", str(log),
                               "--no-progress"])
    out = []
    if code != 2 or "t.csv" not in output:
        out.append(f"--json naming the input: exit {code}, {output.strip()[-200:]!r}; "
                   "expected 2 naming it")
    if log.read_text(encoding="utf-8") != text:
        out.append("the input trace was overwritten")
    return out


#: the end-to-end checks, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("audit-keys", ("TOR-VER-001", "TOR-VER-002", "TOR-VER-003", "TOR-VER-008",
                         "TOR-TCK-007"),
          "fretc audit of the 288 key sentences on CSV traces against the reference",
          check_audit_keys),
    Check("audit-streamed-csv", ("TOR-LOG-003",),
          "CSV traces judged as read give the whole-trace judge's JSON", check_streamed_csv),
    Check("audit-verdicts", ("TOR-VER-003", "TOR-VER-005", "TOR-VER-006", "TOR-VER-007",
                             "TOR-GRM-002"),
          "verdicts, evidence, robustness and exit codes 0, 1, 2", check_verdicts_and_exit),
    Check("audit-unknown", ("TOR-VER-004", "TOR-DMG-003", "TOR-DMG-004", "TOR-VER-006"),
          "unknown cells, NaN and a cut: three-valued verdicts, exit 3", check_unknown),
    Check("outputs-inputs", ("TOR-OUT-001",),
          "an output naming an input is refused, the input kept", check_outputs_over_inputs),
)
