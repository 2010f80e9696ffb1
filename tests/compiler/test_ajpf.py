"""AJPF property files (--emit psl)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from fretc.compiler.ajpf import AjpfError, emit_psl, to_ajpf
from fretc.compiler.build import compile_entry
from fretc.compiler.semantics import formalize
from fretc.fretish import parse


def compiled(rid: str, text: str):
    return compile_entry(SimpleNamespace(
        id=rid, text=text, source="req.fret", line=1, column=1, rationale=None, parent=None,
        tick_period=None, requirement=parse(text), error=None, extra={}))


@pytest.mark.tor("TOR-GEN-004")
def test_r1_is_the_property_safe_ros_verified():
    out = emit_psl([compiled("R1", "whenever too_close agilex_agent shall eventually "
                                   "satisfy stopped")])
    lines = [l for l in out["req"].splitlines() if not l.startswith("#")]
    assert lines == ["R1: [] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))"]


@pytest.mark.tor("TOR-GEN-004")
def test_iff_and_xor_are_rewritten_and_binary_parenthesized():
    f = formalize(parse("the sw shall always satisfy (a <-> b) | (c xor d)")).ft_inf
    text = to_ajpf(f, "ag", {})
    assert "<->" not in text and "xor" not in text
    assert text == ("[] (((B(ag,a) -> B(ag,b)) & (B(ag,b) -> B(ag,a))) || "
                    "((B(ag,c) & ~B(ag,d)) || (~B(ag,c) & B(ag,d))))")


@pytest.mark.parametrize("text,reason", [
    ("upon p the sw shall eventually satisfy q", "next operator"),
    ("whenever p the sw shall within 3 ticks satisfy q", "bounded"),
    ("the sw shall always satisfy alt > 100", "comparison"),
    ("the sw shall finally satisfy q", "nothing for AJPF"),
    ("whenever persisted(2, p) the sw shall eventually satisfy q", "past-time"),
    ("the sw shall always satisfy Q_high", "Gwendolen term"),
])
@pytest.mark.tor("TOR-GEN-004")
def test_refusals_say_why(text, reason):
    with pytest.raises(AjpfError, match=reason):
        to_ajpf(formalize(parse(text)).ft_inf, "sw", {})


@pytest.mark.tor("TOR-GEN-004")
def test_mapping_makes_percepts_actions_and_named_comparisons(tmp_path):
    m = tmp_path / "map.toml"
    m.write_text('agent = "robot"\n[variables.obstacle]\nkind = "percept"\n'
                 'name = "obstacle_seen"\n[variables.halt]\nkind = "action"\nname = "stop"\n'
                 '[comparisons]\n"(alt > 100)" = "high"\n')
    out = emit_psl([compiled("S-1.a", "whenever obstacle sw shall eventually satisfy halt"),
                    compiled("S-2", "the sw shall always satisfy alt > 100")],
                   mapping_path=str(m))
    lines = [l for l in out["req"].splitlines() if not l.startswith("#")]
    assert lines == ["S_1_a: [] (P(obstacle_seen) -> <> D(robot,stop))", "S_2: [] B(robot,high)"]


@pytest.mark.tor("TOR-GEN-004")
def test_unsupported_requirements_become_comments_and_labels_are_unique():
    free = compile_entry(SimpleNamespace(  # (a free-form requirement: no FRETish to parse)
        id="F", text="the robot must not hit anything", source="req.fret", line=1, column=1,
        rationale=None, parent=None, tick_period=None, requirement=None, error=None, extra={}))
    out = emit_psl([compiled("A", "whenever p sw shall eventually satisfy q"),
                    compiled("A", "upon p sw shall eventually satisfy q"),
                    compiled("A", "whenever q sw shall eventually satisfy p"),
                    compiled("A.", "whenever q sw shall eventually satisfy q"), free])["req"]
    labels = [l.split(":")[0] for l in out.splitlines() if not l.startswith("#")]
    assert labels == ["A", "A_2", "A_"]
    out = emit_psl([compiled(rid, "whenever p sw shall eventually satisfy q")
                    for rid in ("A", "A", "A")])["req"]
    assert [l.split(":")[0] for l in out.splitlines() if not l.startswith("#")] == \
        ["A", "A_2", "A_3"]
    out = emit_psl([compiled("A", "upon p sw shall eventually satisfy q"), free])["req"]
    assert "# A: upon p sw shall eventually satisfy q" in out
    assert "#   no AJPF property: AJPF has no next operator" in out
    assert "# F: the robot must not hit anything\n#   not formalized: " in out


@pytest.mark.tor("TOR-GEN-004")
def test_release_keeps_its_operands_in_order():
    """FRET's ``before`` is a release (V): its left operand the one that releases."""
    f = formalize(parse("the sw shall before s satisfy r")).ft_inf
    assert to_ajpf(f, "ag", {}) == "(B(ag,r) R ~B(ag,s))"


def _ajpf_read(text: str) -> list[tuple[str, str]]:
    """AJPF's property-file rule: a line starting with ``#`` is skipped; every other line
    is ``label: formula`` (a line without a colon continues the property above)."""
    props: list[list[str]] = []
    for line in text.splitlines():
        if line.startswith("#") or not line.strip():
            continue
        if ":" in line:
            label, formula = line.split(":", 1)
            props.append([label, formula.strip()])
        else:
            props[-1][1] += " " + line.strip()
    return [(a, b) for a, b in props]


def test_psl_comments_are_hash_lines_ajpf_skips(tmp_path):
    from fretc.compiler.ajpf import emit_psl
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements

    f = tmp_path / "req.fret"
    f.write_text("R1: whenever p the sw shall eventually satisfy q\n"
                 "R2: upon p the sw shall within 3 ticks satisfy q\n"
                 "R3: the sw shall always satisfy !q\n")
    out = emit_psl(compile_entries(load_requirements([str(f)])))["req"]
    # R2 has no AJPF form (a next operator): its reason is a comment, not a property
    assert [label for label, _ in _ajpf_read(out)] == ["R1", "R3"]
    assert all(line.startswith("#") or line.split(":")[0] in ("R1", "R3")
               for line in out.splitlines())
