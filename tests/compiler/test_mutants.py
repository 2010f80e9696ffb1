"""Mutants (compiler/mutants.py) and coverage obligations (compiler/coverage.py) of parsed
requirements: the operators and obligations expected for each field, every mutant and
variant formalizes, and a requirement's variant changes only its own part."""

from __future__ import annotations

from fractions import Fraction

from fretc.compiler.coverage import obligations
from fretc.compiler.mutants import mutants
from fretc.compiler.semantics import formalize
from fretc.fretish.parser import parse

R = "in docking mode upon too_close & armed the robot shall within 10 ticks satisfy stopped"


def test_mutant_operators_and_all_formalize():
    req = parse(R)
    got = mutants(req, 10)
    names = [n for n, _ in got]
    assert "timing n-1" in names and "timing n+1" in names
    assert "condition: negate too_close" in names
    assert "condition: too_close -> armed" in names
    assert "condition: and/or swap #1" in names
    assert "scope notin" in names and "timing eventually" in names
    assert len(set(map(repr, (m for _, m in got)))) == len(got)
    assert repr(req) not in {repr(m) for _, m in got}
    for _, m in got:
        formalize(m, Fraction(1, 10))


def test_obligations_of_each_field():
    req = parse(R)
    obs = {o.id: o for o in obligations("R", req, 10)}
    for oid in ("trigger", "scope-entered", "scope-left", "deadline-reached",
                "deadline-missed", "timing:eventually", "scope:docking+",
                "condition:too_close+", "condition:armed-", "response:stopped+"):
        assert oid in obs, oid
    assert obs["deadline-reached"].variant_ticks == 9
    assert obs["deadline-missed"].variant_ticks == 11
    assert "too_close's own effect" in obs["condition:too_close+"].description
    # the variant of an atom obligation changes that atom only
    v = obs["condition:too_close+"].variant
    assert v.response == req.response and v.scope == req.scope and v.timing == req.timing
    for o in obs.values():
        if o.variant is not None:
            formalize(o.variant, None)


def test_threshold_obligations_only_for_a_variable_and_a_number():
    obs = [o.id for o in obligations("R", parse("the sw shall always satisfy x < 0.9 & y > z"),
                                     None)]
    assert "response:x < 0.9:true" in obs and "response:x < 0.9:false" in obs
    assert not any(o.startswith("response:y > z:") for o in obs)
