"""Several entity kinds in one binding file (docs/bindings.md, "One verdict per entity"):
an ArduPlane log's parameters (``PARM``, each logged once) as three kinds on one key, every
parameter, the failsafe ones (``FS_*``) and the statistics (``STAT_*``), in one
``[entities]`` table. Each requirement is judged over its own kind, with the verdicts it has
in a binding file of that kind alone (the differential test), and an entity's evidence names
its own message, not the newest ``PARM`` record at the tick (another parameter's); a
violated ``!=`` gives no margin of -4.94e-324 but says why it has none."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.audit import AuditConfig, audit_log, load_plan

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "logs"))
from _dataflash import write_dataflash  # noqa: E402

KINDS = {
    "param": """param = '"PARM".Name'""",
    "fs_param": """fs_param = { key = '"PARM".Name', matching = "FS_*" }""",
    "stat_param": """stat_param = { key = '"PARM".Name', matching = "STAT_*" }""",
}
VARIABLES = {
    "param": """value = '"PARM"{Name==$param}.Value'""",
    "fs_param": """fs_value = '"PARM"{Name==$fs_param}.Value'""",
    "stat_param": """stat_value = '"PARM"{Name==$stat_param}.Value'""",
}
FRET = {
    "param": "P1: the plane shall always satisfy value > -1000\n",
    "fs_param": "FS1: the plane shall always satisfy fs_value != 0\n",
    "stat_param": "ST1: the plane shall always satisfy stat_value >= 0\n",
}


def _bindings(kinds) -> str:
    return ('[tick]\nperiod = "100 ms"\n[entities]\n' + "\n".join(KINDS[k] for k in kinds)
            + "\n[variables]\n" + "\n".join(VARIABLES[k] for k in kinds) + "\n")


def _audit(tmp: Path, kinds, log: Path) -> dict:
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "p.fret").write_text("@tick_period 100 ms\n" + "".join(FRET[k] for k in kinds))
    (tmp / "p.bindings.toml").write_text(_bindings(kinds))
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "p.fret"),))), str(log))
    return {v.requirement: v for v in la.verdicts}


def _log(tmp: Path, params: list[tuple[str, float]]) -> Path:
    """One PARM record each, 7 ms apart from 1 s, then battery records to 2 s (the ticks go
    on after the parameters)."""
    rows = [("PARM", [1_000_000 + k * 7_000, n, v]) for k, (n, v) in enumerate(params)]
    rows += [("BAT", [1_000_000 + k * 100_000, 0, 12.0, 1.0, 50.0]) for k in range(11)]
    return write_dataflash(tmp / "params.bin", sorted(rows, key=lambda r: r[1][0]))


def _seen(v) -> tuple:
    fv = v.first_violation
    return (v.requirement, v.verdict, v.error, v.ticks_evaluated,
            None if fv is None else (fv.at.tick, fv.at.time_ns, fv.at.log_time_ns))


PARAMS = [("ARSPD_FBW_MIN", 9.0), ("FS_SHORT_ACTN", 0.0), ("STAT_RUNTIME", 513.0),
          ("COMPASS_OFS_X", -12.0), ("FS_LONG_ACTN", 2.0), ("STAT_BOOTCNT", -1.0),
          ("COMPASS_ODI3_X", 0.0), ("THR_MAX", 100.0)]


def test_three_kinds_in_one_file_each_judged_over_its_own(tmp_path):
    """Every per-entity requirement is judged (no ``$param has no value`` error), each over
    its own kind, with the verdicts the file of its kind alone gives."""
    log = _log(tmp_path, PARAMS)
    together = _audit(tmp_path / "all", list(KINDS), log)
    assert not [v.error for v in together.values() if v.error], together
    assert together["FS1"].verdict == "violated"
    assert together["FS1[fs_param=FS_SHORT_ACTN]"].verdict == "violated"
    assert together["ST1[stat_param=STAT_BOOTCNT]"].verdict == "violated"
    assert together["P1"].verdict == "satisfied"
    assert sorted(k for k in together if k.startswith("FS1[")) == [
        "FS1[fs_param=FS_LONG_ACTN]", "FS1[fs_param=FS_SHORT_ACTN]"]
    for kind in KINDS:
        alone = _audit(tmp_path / kind, [kind], log)
        assert [_seen(v) for v in alone.values()] == [
            _seen(together[k]) for k in alone], kind


def test_an_entity_evidence_names_its_own_message(tmp_path):
    """``FS1[fs_param=FS_SHORT_ACTN]`` is violated at the tick after its record; the
    deciding message of its trigger and of its first violation is its own record (at 1.007
    s), not the newest PARM record at that tick (THR_MAX's, at 1.049 s)."""
    log = _log(tmp_path, PARAMS)
    v = _audit(tmp_path, ["fs_param"], log)["FS1[fs_param=FS_SHORT_ACTN]"]
    own = (1_000_000 + 1 * 7_000) * 1000
    fv = v.first_violation
    assert fv.at.time_ns == 1_100_000_000  # the first tick at or after it
    assert fv.at.log_time_ns == own, fv.at
    assert fv.trigger is not None and fv.trigger.log_time_ns == own, fv.trigger
    src = v.sources.get("PARM") or next(iter(v.sources.values()))
    assert all(lt == own for _i, _t, lt in src), src


def test_a_violated_inequality_has_no_meaningless_margin(tmp_path):
    """``fs_value != 0`` violated by ``FS_SHORT_ACTN = 0``: no robustness of -4.94e-324
    (the smallest double, which tells no distance), a note saying why none is given; the
    satisfied entity's margin is its distance to 0."""
    got = _audit(tmp_path, ["fs_param"], _log(tmp_path, PARAMS))
    bad, good = got["FS1[fs_param=FS_SHORT_ACTN]"], got["FS1[fs_param=FS_LONG_ACTN]"]
    assert bad.robustness is None
    assert any(n.startswith("robustness: none: the violation is decided at distance 0")
               for n in bad.notes), bad.notes
    assert got["FS1"].robustness != -5e-324 and (got["FS1"].robustness is None
                                                  or got["FS1"].robustness >= 0)
    assert good.verdict == "satisfied"
    assert good.robustness in (None, 2.0)  # (judged at once: see the batch's evidence)


NAMES = st.sampled_from(["FS_A", "FS_B", "STAT_A", "STAT_B", "X_A", "X_B"])


@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(params=st.lists(st.tuples(NAMES, st.sampled_from([-1.0, 0.0, 1.0, 2.0])),
                       min_size=1, max_size=12))
def test_kinds_together_equal_each_alone(tmp_path_factory, params):
    """Random parameter logs (a name may repeat, each record a new value): the verdicts of
    each kind's requirement in the file of three kinds equal those of the file of its kind
    alone, entity by entity."""
    tmp = tmp_path_factory.mktemp("kinds")
    log = _log(tmp, params)
    together = _audit(tmp / "all", list(KINDS), log)
    for kind in KINDS:
        alone = _audit(tmp / kind, [kind], log)
        assert [_seen(v) for v in alone.values()] == [_seen(together[k]) for k in alone]


@pytest.mark.parametrize("missing", ["fs_param"])
def test_a_requirement_of_a_kind_whose_variable_is_missing_is_its_own_error(tmp_path, missing):
    """A kind whose variable is not bound: only its requirement is an error, the others
    are judged."""
    kinds = list(KINDS)
    (tmp_path / "p.fret").write_text("@tick_period 100 ms\n" + "".join(FRET[k] for k in kinds))
    text = _bindings(kinds).replace(VARIABLES[missing] + "\n", "")
    (tmp_path / "p.bindings.toml").write_text(text)
    got = {v.requirement: v for v in audit_log(load_plan(AuditConfig(
        requirements=(str(tmp_path / "p.fret"),))), str(_log(tmp_path, PARAMS))).verdicts}
    assert got["FS1"].verdict == "error" and "fs_value" in got["FS1"].error
    assert got["P1"].verdict == "satisfied" and got["ST1"].verdict == "violated"
