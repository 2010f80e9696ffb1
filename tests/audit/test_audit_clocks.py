"""Per-requirement clocks: a requirement's verdict and evidence depend only on the
requirement, its bindings and the log - never on the other requirements audited with it
(../shared/DESIGN.md, "Each verdict stands alone"). Each shipped requirement is audited alone and in
random groups on the shipped traces and must give identical JSON."""

from __future__ import annotations

import dataclasses
import json
import random
from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan

ROOT = Path(__file__).resolve().parents[2]
TRACES = sorted((ROOT / "traces").glob("*.mcap"))


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


def _subset(plan, ids):
    return dataclasses.replace(plan, requirements=[r for r in plan.requirements if r.id in ids])


def _verdicts(plan, log):
    doc = audit_log(plan, str(log)).to_json()
    return {v["requirement"]: json.dumps(v, sort_keys=True) for v in doc["verdicts"]}


def _check(plan, log, groups):
    ids = [r.id for r in plan.requirements]
    alone = {}
    for rid in ids:
        alone.update(_verdicts(_subset(plan, {rid}), log))
    for group in groups:
        got = _verdicts(_subset(plan, set(group)), log)
        for rid, doc in got.items():
            assert doc == alone[rid], f"{rid} on {log.name} differs in group {sorted(group)}"


def test_r4_alone_and_in_the_main_job_agree(plan):
    """The case of the issue: R4 alone on nominal.mcap ran 877 ticks from 0.05 s, in the
    main job 876 ticks from 0.0 s with a warm-up tick."""
    log = ROOT / "traces" / "nominal.mcap"
    a = json.loads(_verdicts(_subset(plan, {"R4"}), log)["R4"])
    b = json.loads(_verdicts(plan, log)["R4"])
    assert (a["ticks_evaluated"], a["warmup_ticks"]) == (b["ticks_evaluated"], b["warmup_ticks"])
    assert a["warmup_ticks"] == 0  # R4 reads /cmd_vel_filtered only: its grid starts there
    assert a == b


def test_alone_and_in_random_groups_agree_on_two_traces(plan):
    """Bounded sample for the default run: two traces (one with violations), three random
    groups each."""
    rng = random.Random(10)
    ids = [r.id for r in plan.requirements]
    for name in ("sif_disabled.mcap", "lidar_dropout.mcap"):
        groups = [rng.sample(ids, rng.randint(2, len(ids))) for _ in range(3)] + [ids]
        _check(plan, ROOT / "traces" / name, groups)


@pytest.mark.slow
@pytest.mark.parametrize("log", TRACES, ids=lambda p: p.name)
@pytest.mark.tor("TOR-TCK-001")
def test_alone_and_in_random_groups_agree_on_every_trace(plan, log):
    rng = random.Random(log.name)
    ids = [r.id for r in plan.requirements]
    groups = [rng.sample(ids, rng.randint(2, len(ids))) for _ in range(6)] + [ids]
    _check(plan, log, groups)


def test_a_binding_that_reads_the_previous_message_shifts_no_neighbour(tmp_path):
    """``x_step = "/v.x@delta"`` waits for the second message of /v; ``A: always x_val <= 5``
    on the same topic is still judged from the first, where x = 10 violates it, alone and
    beside the @delta requirement alike (it used to be satisfied beside it)."""
    import json as _json

    from mcap.writer import Writer

    log = tmp_path / "v.mcap"
    with open(log, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("V", "jsonschema", _json.dumps(
            {"type": "object", "properties": {"x": {"type": "number"}}}).encode())
        cid = w.register_channel("/v", "json", sid)
        for i, x in enumerate([10, 1, 2, 3, 2, 1]):
            t = 1_000_000_000 + i * 100_000_000
            w.add_message(cid, t, _json.dumps({"x": x}).encode(), t)
        w.finish()
    (tmp_path / "r.fret").write_text("A: the sw shall always satisfy x_val <= 5\n"
                                     "B: the sw shall always satisfy x_step <= 100\n")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nx_val = "/v.x"\nx_step = "/v.x@delta"\n')
    both = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    got = _verdicts(both, log)
    alone = _verdicts(_subset(both, {"A"}), log)
    assert got["A"] == alone["A"]
    a, b = _json.loads(got["A"]), _json.loads(got["B"])
    assert a["verdict"] == "violated" and a["first_violation"]["tick"] == 0
    assert a["warmup_ticks"] == 0 and b["warmup_ticks"] == 1
    assert b["verdict"] == "satisfied"
