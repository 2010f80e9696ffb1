"""Random safety requirement sets, random inputs and random proposals (hypothesis): every
shield keeps its requirements, lets a safe proposal through unchanged, and changes an
unsafe one as little as any safe output could (brute force); FRET's interval semantics
(the audit's judge, independent of the game's pt monitors) finds no enforced requirement
violated on the corrected trace; and the Spot proof agrees."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from fretc.shield.emit_python import tables
from fretc.shield.plan import ShieldError
from fretc.shield.prove import prove_shield
from fretc.shield.runtime import ShieldRuntime

from _gen import (atoms_of, best_cost, build, compile_text, cost, requirement_sets, runs,
                  safe, verdicts)

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _shield(text: str, prefer_seed: int = 0):
    with tempfile.TemporaryDirectory() as tmp:
        compiled = compile_text(text, Path(tmp))
        try:
            shield = build(compiled)
        except ShieldError:
            assume(False)
        texts = sorted({a.text for m in shield.machines for a in m.outputs})
        if prefer_seed and texts:
            prefer = [(texts[(prefer_seed + k) % len(texts)], bool((prefer_seed >> k) & 1))
                      for k in range(min(2, len(texts)))]
            prefer = list(dict(prefer).items())
            shield = build(compiled, prefer=prefer)
    return compiled, shield


@SETTINGS
@given(text=requirement_sets(), run=runs(), prefer_seed=st.integers(0, 7))
@pytest.mark.tor("TOR-SHD-001")
def test_a_shield_keeps_its_requirements_and_interferes_least(text, run, prefer_seed):
    compiled, shield = _shield(text, prefer_seed)
    enforced = {r.id for r in shield.requirements}
    rt = ShieldRuntime(tables(shield))
    trace = []
    for ins, prop in run:
        before = [m.state for m in rt.machines]
        d = rt.step(ins, prop)
        all_safe = True
        for k, m in enumerate(shield.machines):
            p, o = atoms_of(m, prop), atoms_of(m, d.outputs)
            assert safe(m, before[k], ins, o), (text, ins, prop, d)
            if safe(m, before[k], ins, p):
                assert o == p, (text, ins, prop, d)
            else:
                all_safe = False
                w = shield.weights(k)
                assert cost(o, p, w, 1 << len(w)) == best_cost(m, before[k], ins, p, w)
                assert set(d.reasons) & set(m.requirements), d
        if all_safe:
            assert not d.overridden and d.outputs == prop and d.reasons == ()
        else:
            assert d.overridden and d.changed
        trace.append({**ins, **d.outputs})
        if d.overridden:
            event("overridden")
    got = verdicts(compiled, trace)
    assert all(got[r] != "violated" for r in enforced), (text, got, trace)


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=requirement_sets())
@pytest.mark.tor("TOR-SHD-001", "TOR-SHD-002")
def test_the_closed_loop_of_every_shield_is_proved(text):
    compiled, shield = _shield(text)
    proof = prove_shield(shield, compiled)
    assert not proof.blocking
    assert all(v in ("holds", "unknown") for v in proof.results.values()), proof.text()
    assert set(proof.results) == {r.id for r in shield.requirements}


def test_a_table_that_differs_from_the_games_bdd_is_never_exported(monkeypatch, tmp_path):
    # the synthesis compares every exported root with BuDDy's BDD: a corrupted copy (one
    # node's branches swapped) is an internal error, not a shield
    from fretc.shield import synthesis

    real_add = synthesis._Table.add
    done = []

    def corrupt(self, f):
        got = real_add(self, f)
        if len(self.nodes) > 2 and not done:
            done.append(1)
            var, lo, hi = self.nodes[2]
            self.nodes[2] = (var, hi, lo)
        return got

    monkeypatch.setattr(synthesis._Table, "add", corrupt)
    compiled = compile_text("R1: whenever a sw shall immediately satisfy x\n", tmp_path)
    import pytest

    with pytest.raises(RuntimeError, match="differs from the game's BDD"):
        build(compiled)
