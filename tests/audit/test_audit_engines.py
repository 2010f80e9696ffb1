"""The audit decides each requirement by its own engine: a binding failing on the log is an
error of the requirements that use it alone, and a future-time function (no pt monitor) is
decided offline by the interval semantics."""

from __future__ import annotations

from fretc.audit import audit_log
from test_audit import SYN_BINDINGS, SYN_FRET, _by_req, _plan, _synthetic


def test_a_binding_that_fails_on_the_log_is_an_error_of_its_requirements_only(tmp_path):
    path = _synthetic(tmp_path)
    (tmp_path / "syn.fret").write_text(SYN_FRET + "A5: the bot shall always satisfy wobble < 1\n")
    (tmp_path / "syn.bindings.toml").write_text(SYN_BINDINGS + 'wobble = "/cmd.linear.q"\n')
    la = audit_log(_plan(tmp_path / "syn.fret"), str(path))
    v = _by_req(la)
    assert v["A5"].verdict == "error" and "no field 'q'" in v["A5"].error
    assert [v[r].verdict for r in ("A1", "A2", "A3")] == ["satisfied"] * 3


def test_future_time_function_is_decided_offline(tmp_path):
    """No online monitor exists for persists(...) (pt needs the future); the audit decides it
    by the interval semantics, equal to the reference ft evaluator."""
    from fretc.compiler.evaluate import ft_at

    (tmp_path / "f.fret").write_text("F1: whenever p the sw shall immediately satisfy "
                                     "persists(2, q)\n")
    rows = ["p,q", "0,0", "1,1", "0,1", "0,1", "1,1", "0,1", "0,0"]
    (tmp_path / "f.csv").write_text("\n".join(rows) + "\n")
    plan = _plan(tmp_path / "f.fret")
    r = plan.requirements[0]
    assert r.offline and r.monitor_cls is None and r.error is None
    la = audit_log(plan, str(tmp_path / "f.csv"))
    v = la.verdicts[0]
    trace = [{"p": a == "1", "q": b == "1"} for a, b in (x.split(",") for x in rows[1:])]
    expected = ft_at(r.formalization.ft, trace)
    assert v.engine == "interval" and (v.verdict != "violated") == expected
    assert v.verdict == "violated" and v.first_violation.trigger.tick == 4
