"""``fretc audit --json`` of many entities keeps its memory bounded per entity: the entities
judged at once are records (audit/entities/verdicts.py) and the document is written verdict
by verdict (:func:`fretc.audit.verdict.write_audit_json`), the same text as the document
made whole. 10^6 entities with ``--json`` took 7.6 GB, then ``internal error:
MemoryError``; about 10 KB of JSON state per entity (docs/performance.md gives today's
figures for 10^6)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.verdict import audit_json, write_audit_json
from test_entities_evidence import NEAR, _plan, _tracks

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))


def _logs(tmp: Path, entities: int) -> Path:
    from bench_audit import ENTITY_BINDINGS, ENTITY_REQUIREMENTS
    from tracks_run import write_many_tracks

    (tmp / "t.fret").write_text(ENTITY_REQUIREMENTS)
    (tmp / "t.bindings.toml").write_text(ENTITY_BINDINGS)
    log = tmp / f"many_{entities}.mcap"
    write_many_tracks(log, entities)
    return log


def _peak_kb(tmp: Path, log: Path, json_out: str) -> int:
    """The peak memory (KB) of ``fretc audit LOG --json OUT`` in a process of its own
    (started from a small one: the peak is its own)."""
    code = ("import resource, sys\nfrom fretc.cli import main\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    code = e.code\n"
            "sys.stderr.write(f'PEAK {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}"
            " {code}\\n')\n")
    run = subprocess.run([sys.executable, "-c", code, "audit", "-r", str(tmp / "t.fret"),
                          str(log), "--no-progress", "--json", json_out],
                         capture_output=True, text=True, timeout=600, cwd=tmp)
    line = next(x for x in run.stderr.splitlines() if x.startswith("PEAK "))
    _, kb, exit_code = line.split()
    assert exit_code == "1", run.stderr  # (1,000 of 100,000 obstacles violate it: a few here)
    return int(kb)


def test_json_of_many_entities_grows_by_little_per_entity(tmp_path):
    """4,000 and 24,000 entities with ``--json``: the peak grows by less than 1.5 KB an
    entity (it grew by about 10 KB), and the file is the document of the audit in memory."""
    small, large = _logs(tmp_path, 4_000), _logs(tmp_path, 24_000)
    a = _peak_kb(tmp_path, small, str(tmp_path / "a.json"))
    b = _peak_kb(tmp_path, large, str(tmp_path / "b.json"))
    assert (b - a) / 20_000 < 1.5, (a, b)
    doc = json.loads((tmp_path / "b.json").read_text())
    assert len(doc["logs"][0]["verdicts"]) == 24_001
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
    la = audit_log(plan, str(large))
    assert doc["logs"][0]["verdicts"] == json.loads(json.dumps(la.to_json()))["verdicts"]


_JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.text(max_size=5)
                     | st.floats(allow_nan=False, allow_infinity=False),
                     lambda inner: st.lists(inner, max_size=3)
                     | st.dictionaries(st.text(max_size=4), inner, max_size=3), max_leaves=12)


_AUDITS: list = []


def _audit(tmp: Path):
    """A log's audit with plain and per-entity verdicts (made once)."""
    if not _AUDITS:
        rows = [{1: 2.0, 2: 0.4}, {2: 2.0, 3: 0.8}, {}]
        plan = _plan(tmp, "R: in present mode the robot shall always satisfy dist > 0.5\n"
                     "P: the robot shall always satisfy dist < 100\n", NEAR)
        _AUDITS.append(audit_log(plan, str(_tracks(tmp, rows))))
    return _AUDITS[0]


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(extra=st.dictionaries(st.text(min_size=1, max_size=6).filter(
    lambda k: k not in ("schema", "requirements", "bindings", "logs", "summary")), _JSON,
    max_size=3), bindings=_JSON, requirements=st.lists(st.dictionaries(
        st.sampled_from(["id", "text"]), st.text(max_size=4)), max_size=2))
def test_the_document_written_piece_by_piece_is_the_whole_documents_text(
        tmp_path_factory, extra, bindings, requirements):
    """Whatever its other members, the document written verdict by verdict is the text of
    ``json.dumps(doc, indent=2, sort_keys=True)`` of the whole document (the audit of a log
    with plain and per-entity verdicts, none, and an empty log list)."""
    la = _audit(tmp_path_factory.mktemp("doc"))
    for logs in ([la], [], [la, la]):
        parts: list[str] = []
        write_audit_json(parts.append, logs, requirements, bindings, False, False, extra)
        whole = {"schema": json.loads(audit_json(logs, requirements, bindings))["schema"],
                 "requirements": requirements, "bindings": bindings,
                 "logs": [x.to_json() for x in logs], **extra}
        text = "".join(parts)
        summary = json.loads(text)["summary"]
        whole["summary"] = summary
        assert text == json.dumps(whole, indent=2, sort_keys=True, allow_nan=False) + "\n"
        assert audit_json(logs, requirements, bindings, False, False, extra) == text
