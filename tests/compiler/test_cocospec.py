"""``fretc --emit cocospec``: Kind 2 itself does not install here (neither PyPI nor Debian has
it), so each contract is read back by the tests' own Lustre-subset reader and interpreter
(``tests/_lustre_subset.py``): the text is well formed (nodes and one contract, each
``let`` closed by ``tel``), every name a guarantee reads is declared and every node it calls
defined, and -- the differential -- the guarantee's stream, computed from the emitted Lustre
nodes, equals fretc's reference evaluator (``compiler/evaluate.py``'s ``series``) of the same
pt formula at every tick of random traces; on FRET's case studies it also equals the stream
of FRET's own ``CoCoSpecCode``. What Lustre cannot say is left out with the reason."""

from __future__ import annotations

import json
import random
import re
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st

from fretc.cli import main
from fretc.compiler import ir
from fretc.compiler.build import compile_entries
from fretc.compiler.cocospec import LIBRARY, emit_cocospec, library_text, lustre
from fretc.compiler.evaluate import series
from fretc.fretish.files import load_requirements

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import _lustre_subset as lus  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _formulas() -> st.SearchStrategy:
    leaves = st.sampled_from([ir.ap("p"), ir.ap("q"), ir.TRUE, ir.FALSE, ir.FTP,
                              ir.cmp(">", ir.var("x"), ir.num("2")),
                              ir.cmp("<=", ir.arith("+", ir.var("x"), ir.num("1.5")),
                                     ir.num("3")),
                              ir.cmp("<", ir.arith("+", ir.var("k"), ir.num("1")), ir.var("x")),
                              ir.cmp(">=", ir.arith("/", ir.var("k"), ir.num("2")), ir.num("1")),
                              ir.cmp("=", ir.arith("mod", ir.var("k"), ir.num("2")), ir.num("0"))
                              ])
    window = st.tuples(st.integers(0, 4), st.integers(0, 4)).map(sorted)

    def grow(sub):
        unary = st.sampled_from(["!", "Y", "Z", "O", "H"])
        binary = st.sampled_from(["&", "|", "->", "<->", "xor", "S", "T"])
        return st.one_of(
            st.builds(lambda op, a: ir.Node(op, (a,)), unary, sub),
            st.builds(lambda op, a, b: ir.Node(op, (a, b)), binary, sub, sub),
            st.builds(lambda op, w, a: ir.Node(op, (a,), lo=w[0], hi=w[1]),
                      st.sampled_from(["O", "H"]), window, sub))

    return st.recursive(leaves, grow, max_leaves=8)


def _trace(rng: random.Random, n: int) -> list[dict]:
    return [{"p": rng.random() < 0.5, "q": rng.random() < 0.5,
             "x": rng.choice([0.0, 1.0, 2.5, 3.0]), "k": rng.choice([0, 1, 2, 3, 4])}
            for _ in range(n)]


def _contract_text(formula: ir.Node) -> str:
    used: set[str] = set()
    expr = lustre(formula, {"p": "p", "q": "q", "x": "x", "k": "k"}, {"x": "real", "k": "int"},
                  used)
    return (library_text(used) + "\ncontract C(p, q: bool; x: real; k: int) returns ();\n"
            f"let\n  guarantee \"g\" {expr};\ntel\n")


@settings(max_examples=300, deadline=None, derandomize=True)
@given(_formulas(), st.integers(0, 2 ** 32 - 1))
def test_the_lustre_nodes_compute_the_pt_formula_at_every_tick(formula, seed):
    """Differential: the emitted Lustre (fretc's operator nodes included) interpreted tick by
    tick equals the reference evaluator of the same pt formula."""
    program = lus.read(_contract_text(formula))
    trace = _trace(random.Random(seed), 14)
    got = lus.run_contract(program, "C", trace)["\"g\""]
    assert got == [bool(v) for v in series(formula, trace)]


def test_every_operator_node_is_exercised_and_defined():
    """Each of FRET's operators is reached by a formula of its own, and the library holds
    exactly the nodes the text calls (with those they call)."""
    p, q = ir.ap("p"), ir.ap("q")
    cases = {"YtoPre": ir.Y(p), "ZtoPre": ir.Z(p), "H": ir.H(p), "O": ir.O(p),
             "S": ir.S(p, q), "T": ir.T(p, q), "OT": ir.O(p, 2, 3), "HT": ir.H(p, 0, 2)}
    for name, f in cases.items():
        text = _contract_text(f)
        program = lus.read(text)
        assert name in program, (name, text)
        calls = {t for k, t in lus.tokens(text.split("contract C")[1]) if k == "id"}
        assert name in calls
    assert "delay3" not in lus.read(_contract_text(ir.O(p, 0, 3)))
    assert "delay2" in lus.read(_contract_text(ir.O(p, 2, 3)))


def _compiled(paths):
    return compile_entries(load_requirements([str(x) for x in paths]))


def _check_structure(text: str) -> dict:
    """The file reads as nodes and one contract (by the tests' reader, stricter than Kind 2);
    every node is one of fretc's library (no other node); the contract declares each name
    once; every name a guarantee or ghost reads is a parameter or ghost of the contract;
    every node called is defined."""
    program = lus.read(text)
    contracts = [n for n in program.values() if n.kind == "contract"]
    assert len(contracts) == 1
    for name, node in program.items():
        assert node.kind == "contract" or name in LIBRARY or re.fullmatch(
            r"delay[0-9]*", name), f"a node fretc does not write: {name}"
    c = contracts[0]
    names = [v for v, _t in c.params + c.returns + c.locals]
    assert len(names) == len(set(names)), names
    declared = set(names)
    for label, e in [(p[1], p[2]) for p in c.props] + list(c.eqs.items()):
        for name in _names(e):
            assert name in declared, (label, name)
    for node in program.values():
        for e in node.eqs.values():
            for call in _calls(e):
                assert call in program and program[call].kind == "node", call
    return program


def _walk(e):
    if isinstance(e, tuple):
        yield e
        for x in e[1:]:
            if isinstance(x, tuple):
                yield from _walk(x)


def _names(e):
    return {x[1] for x in _walk(e) if x[0] == "id"}


def _calls(e):
    return {x[1] for x in _walk(e) if x[0] == "call"}


def test_safe_ros_contracts_read_back_and_decide_as_the_evaluator(tmp_path):
    """The shipped requirements: one contract per component, well formed, each guarantee's
    stream the reference evaluator's on random traces."""
    compiled = _compiled([ROOT / "requirements/safe_ros.fret", ROOT / "requirements/r1.fret"])
    files, skipped, _notes = emit_cocospec(compiled)
    assert sorted(files) == ["agilex_agentSpec", "cmd_vel_interceptorSpec",
                             "safety_systemSpec", "scout_miniSpec"]
    assert skipped == []
    rng = random.Random(7)
    by_id = {c.id: c for c in compiled}
    for stem, text in files.items():
        program = _check_structure(text)
        c = program[stem]
        for _ in range(20):
            trace = [{v: (rng.random() < 0.5 if t == "bool" else rng.choice([0.0, 0.4, 0.6]))
                      for v, t in c.params} for _ in range(40)]
            got = lus.run_contract(program, stem, trace)
            for label, values in got.items():
                pt = by_id[label.strip('"')].formalization.pt
                assert values == [bool(v) for v in series(pt, trace)], (stem, label)


def test_what_lustre_cannot_say_is_left_out_with_the_reason(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text("@inputs a\n@outputs b, n\n"
                   "A1: the c shall always satisfy b\n"
                   "A2: the c shall always satisfy n ^ 2 > 3\n"
                   "A3: the c shall always satisfy f(n) > 1\n")
    files, skipped, _notes = emit_cocospec(_compiled([src]))
    assert [(rid, why.split(" ")[0]) for _s, rid, why in skipped] == [
        ("A2", "Lustre"), ("A3", "the")]
    assert "power" in skipped[0][2] and "f has no Lustre node" in skipped[1][2]
    text = files["cSpec"]
    assert "-- not here: A2" in text and 'guarantee "A1" H(b);' in text
    program = _check_structure(text)
    assert program["cSpec"].params == [("a", "bool")]
    assert program["cSpec"].returns == [("b", "bool"), ("n", "real")]


def test_numbers_print_in_their_context_type_and_integers_convert(tmp_path):
    """Kind 2 converts nothing itself: literals take their comparison's type, an integer term
    beside a real one is converted with ``real``, FRET's ``/`` is the reals'."""
    src = tmp_path / "r.fret"
    src.write_text("R1: the c shall always satisfy x > 3 & y <= 1e2\n")
    files, skipped, _notes = emit_cocospec(_compiled([src]))
    assert skipped == []
    assert "(x > 3.0)" in files["cSpec"] and "(y <= 100.0)" in files["cSpec"]
    export = tmp_path / "p.json"
    export.write_text(json.dumps({
        "requirements": [{"reqid": "M1", "fulltext": "the c shall always satisfy "
                          "n + 1 > x & n mod 2 = 0 & n / 2 < 3 & absInt(n) >= 1"},
                         {"reqid": "M2", "fulltext": "the c shall always satisfy absInt(x) > 1"}],
        "variables": [{"variable_name": "n", "component_name": "c", "idType": "Input",
                       "dataType": "integer"},
                      {"variable_name": "x", "component_name": "c", "idType": "Input",
                       "dataType": "double"}]}))
    compiled = _compiled([export])
    files, skipped, _notes = emit_cocospec(compiled)
    text = files["cSpec"]
    assert "((real (n + 1)) > x)" in text and "((n mod 2) = 0)" in text
    assert "(((real n) / 2.0) < 3.0)" in text and "(absInt(n) >= 1)" in text
    assert skipped == [("cSpec", "M2", "a real term (x) where Lustre needs an integer")]
    program = _check_structure(text)
    rng = random.Random(5)
    for _ in range(30):
        trace = [{"n": rng.randint(-3, 6), "x": rng.choice([0.5, 2.0, 7.5])} for _ in range(5)]
        got = lus.run_contract(program, "cSpec", trace)['"M1"']
        assert got == [bool(v) for v in series(compiled[0].formalization.pt, trace)]


def test_the_cli_writes_one_file_per_component_and_refuses_outputs_over_inputs(tmp_path):
    runner = CliRunner()
    out = tmp_path / "out"
    r = runner.invoke(main, ["requirements/safe_ros.fret", "--emit", "cocospec", "-o",
                             str(out)])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == [
        "agilex_agentSpec.lus", "cmd_vel_interceptorSpec.lus", "safety_systemSpec.lus",
        "scout_miniSpec.lus"]
    first = (out / "scout_miniSpec.lus").read_bytes()
    r = runner.invoke(main, ["requirements/safe_ros.fret", "--emit", "cocospec", "-o",
                             str(out)])
    assert (out / "scout_miniSpec.lus").read_bytes() == first  # same input, same bytes
    src = tmp_path / "scout_miniSpec.lus"
    src.write_text("R5: the scout_mini shall always satisfy clearance > 0\n")
    r = runner.invoke(main, [str(src), "--emit", "cocospec", "-o", str(tmp_path)])
    assert r.exit_code == 2 and "scout_miniSpec.lus" in r.output
    assert src.read_text().startswith("R5:")  # the input is not overwritten


def test_a_requirement_left_out_is_named_on_stderr(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text("A2: the c shall always satisfy n ^ 2 > 3\n")
    r = CliRunner().invoke(main, [str(src), "--emit", "cocospec"])
    assert r.exit_code == 0
    assert "skipped A2 (cSpec.lus): Lustre has no power operator" in r.output


_FRET_EXTRA = """
node SI(X, Y: bool) returns (Z: bool);
let
  Z = Y and (X or (false -> pre Z));
tel
node ST(L: int; R: int; X: bool; Y: bool) returns (Z: bool);
let
  Z = S(X, Y) and OT(L, R, X);
tel
node SIT(L: int; R: int; X: bool; Y: bool) returns (Z: bool);
let
  Z = SI(X, Y) and OT(L, R, X);
tel
"""


def _fret_cases(shared: Path):
    for path in sorted((shared / "corpora/fret_projects").glob("*/*.json")):
        data = json.loads(path.read_text())
        reqs = data["requirements"] if isinstance(data, dict) else data
        yield path, {r["reqid"]: r["semantics"].get("CoCoSpecCode") for r in reqs
                     if isinstance(r.get("semantics"), dict)}


def test_fret_case_studies_agree_with_frets_own_cocospec_code(shared):
    """On FRET's case studies, each guarantee fretc writes and FRET's own ``CoCoSpecCode`` of
    the requirement (read with the same interpreter; FRET's ``SI``/``ST``/``SIT`` added as
    FRET defines them, its bare ``FTP`` as the first tick) give the same stream on random
    traces of the contract's variables."""
    rng = random.Random(3)
    compared = 0
    for path, fret_code in _fret_cases(shared):
        files, _skipped, _notes = emit_cocospec(_compiled([path]))
        for stem, text in files.items():
            program = _check_structure(text)
            contract = program[stem]
            kinds = dict(contract.params + contract.returns + contract.locals)
            for _kind, label, _expr in contract.props:
                code = fret_code.get(label.strip('"'))
                if not code or "$" in code:
                    continue
                delays = {f"delay{m}" for m in re.findall(r"T\(\d+, *(\d+)", code)
                          if m != "0"}
                mine = lus.read(library_text(set(LIBRARY) | delays) + _FRET_EXTRA
                                + f"contract F_({_params(kinds)}) returns ();\n"
                                "let\n  var FTP: bool = true -> false;\n"
                                f"  guarantee \"f\" {code};\ntel\n")
                names = {x[1] for x in _walk(mine["F_"].props[0][2]) if x[0] == "id"}
                assert names <= set(kinds) | {"FTP"}, (label, names - set(kinds))
                for _ in range(5):
                    trace = [{v: _value(rng, t) for v, t in kinds.items()} for _ in range(12)]
                    ours = lus.run_contract(_only(program, stem, label), stem, trace)[label]
                    theirs = lus.run_contract(mine, "F_", trace)['"f"']
                    assert ours == theirs, (path.name, label, code)
                compared += 1
    # every requirement fretc writes (those it leaves out read sin, cos, sqrt ...: FRET's
    # Function variables, no Lustre of them here nor in FRET's export)
    assert compared >= 170, compared


def _params(kinds: dict) -> str:
    return "; ".join(f"{v}: {t}" for v, t in kinds.items()) or "lustreC: bool"


def _value(rng: random.Random, ty: str):
    if ty == "bool":
        return rng.random() < 0.5
    return rng.choice([0, 1, 2, 3, 4]) if ty == "int" else rng.choice([0.0, 1.0, 2.5, 4.0])


def _only(program: dict, stem: str, label: str) -> dict:
    """``program`` with contract ``stem`` reduced to its property ``label``, its ghost
    variables read as inputs (as FRET's formula reads them)."""
    c = program[stem]
    one = lus.Node(c.name, c.kind, c.params + c.locals, c.returns, [], {},
                   [p for p in c.props if p[1] == label])
    return {**program, stem: one}


@pytest.mark.parametrize("name", ["H", "O", "S", "T", "YtoPre", "ZtoPre", "OT", "HT"])
def test_fret_operator_names_and_argument_orders(name):
    """FRET's CoCoSpec names and orders: ``a S b`` is ``S(b, a)``, ``O[l,h]`` is
    ``OT(h, l, _)``."""
    p, q = ir.ap("p"), ir.ap("q")
    f = {"H": ir.H(p), "O": ir.O(p), "S": ir.S(p, q), "T": ir.T(p, q), "YtoPre": ir.Y(p),
         "ZtoPre": ir.Z(p), "OT": ir.O(p, 1, 3), "HT": ir.H(p, 1, 3)}[name]
    text = lustre(f, {"p": "p", "q": "q"}, {})
    assert text == {"H": "H(p)", "O": "O(p)", "S": "S(q, p)", "T": "T(q, p)",
                    "YtoPre": "YtoPre(p)", "ZtoPre": "ZtoPre(p)", "OT": "OT(3, 1, p)",
                    "HT": "HT(3, 1, p)"}[name]


def test_a_free_form_requirement_is_in_no_contract(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text('F1: "just words"\nR1: the c shall always satisfy b\n')
    files, skipped, _notes = emit_cocospec(_compiled([src]))
    assert list(files) == ["cSpec"] and skipped == [("-", "F1", "free-form: no formula, "
                                                     "no component")]
    r = CliRunner().invoke(main, [str(src), "--emit", "cocospec"])
    assert "skipped F1: free-form" in r.output and 'guarantee "R1" H(b);' in r.output


def test_a_component_with_nothing_to_write_has_no_empty_contract(tmp_path):
    """Kind 2's grammar wants at least one item in a contract: a component none of whose
    requirements can be written gets a file of comments saying so."""
    src = tmp_path / "r.fret"
    src.write_text("A2: the c shall always satisfy n ^ 2 > 3\n")
    files, skipped, _notes = emit_cocospec(_compiled([src]))
    assert lus.read(files["cSpec"]) == {}  # comments only
    assert "-- no contract: none of c's requirements could be written" in files["cSpec"]
    try:
        lus.read("contract E(a: bool) returns ();\nlet\ntel\n")
    except SyntaxError:
        pass
    else:
        raise AssertionError("the reader takes an empty contract")


def test_a_variable_named_as_a_kind2_keyword_or_operator_node_is_renamed(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text('@inputs merge, H1\nR1: the c shall always satisfy merge & H1 & frame\n')
    files, _skipped, _notes = emit_cocospec(_compiled([src]))
    program = _check_structure(files["cSpec"])
    assert [v for v, _t in program["cSpec"].params] == ["merge_v", "H1", "frame_v"]
    assert 'guarantee "R1" H(((merge_v and H1) and frame_v));' in files["cSpec"]


def test_one_component_goes_to_the_file_o_names(tmp_path):
    out = tmp_path / "mine.lus"
    r = CliRunner().invoke(main, ["requirements/r1.fret", "--emit", "cocospec", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "contract agilex_agentSpec(" in out.read_text()
    r = CliRunner().invoke(main, ["requirements/safe_ros.fret", "--emit", "cocospec", "-o",
                                  str(out)])
    assert r.exit_code == 2 and "one per component" in r.output


# ---------------------------------------------------------------- hostile glossaries
import _hostile_fret as hostile  # noqa: E402

from fretc.common.textsafe import one_line  # noqa: E402
from fretc.compiler.expressions import Expander  # noqa: E402
from fretc.fretish.lustre import parse_definition, print_definition  # noqa: E402


def _export(tmp_path: Path, variables: list, reqs: list) -> Path:
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": reqs, "variables": [
        {"component_name": "c", "dataType": "boolean", **v} for v in variables]}))
    return path


def _label_of(token: str) -> str:
    """The value of a label as Kind 2's lexer reads it (``\\\\c`` is ``c``)."""
    return re.sub(r"\\(.)", r"\1", token[1:-1])


_HOSTILE = [  # (variable, assignment): the report's injection, comments, keywords
    ("k", hostile.INJECTION), ("k2", "a -- ;"), ("k3", "a (* "), ("k4", "node and not let"),
    ("k5", "a and tel"), ("k6", "a /* b */"), ("k7", "a // b"), ("k8", "(a *) b")]


def test_an_injected_or_commented_definition_is_left_out_and_no_foreign_node_written(
        tmp_path):
    """The report's export (an Internal assignment ``a; tel`` + a foreign node + a second
    contract), one holding ``--`` or ``(*``, and ones reading ``node``/``let``/``tel``:
    each is left out with the reason (a comment of the file and a note on stderr), the
    variable read as an input; the file reads back as fretc's nodes and one contract."""
    path = _export(tmp_path, [
        {"variable_name": "a", "idType": "Input"}, {"variable_name": "node", "idType": "Input"},
        {"variable_name": "let", "idType": "Input"}, {"variable_name": "tel", "idType": "Output"},
        *({"variable_name": n, "idType": "Internal", "assignment": text}
          for n, text in _HOSTILE)],
        [{"reqid": "R1", "fulltext": "the c shall always satisfy k & k2 & k3 & a"},
         {"reqid": "R2", "fulltext": "the c shall always satisfy node | tel"}])
    out = tmp_path / "c.lus"
    r = CliRunner().invoke(main, [str(path), "--emit", "cocospec", "-o", str(out)])
    assert r.exit_code == 0, r.output
    text = out.read_text()
    program = _check_structure(text)
    assert set(program) == {"cSpec", "H"} and "evil" not in text.replace("-- ", "#")
    c = program["cSpec"]
    assert c.locals == [] and [v for v, _t in c.params] == [
        "a", "node_v", "let_v", "k", "k2", "k3"]
    assert [v for v, _t in c.returns] == ["tel_v"]
    for name, _text in _HOSTILE:
        assert f"-- not defined here: {name}: its definition is outside FRET's Lustre " \
               "subset" in text
        assert f"note: cSpec: {name} is not defined in the contract" in r.output
    assert "a Lustre comment ('--', character 2)" in text
    assert "'node' (character 0) is outside FRET's Lustre subset" in r.output
    ogma = CliRunner().invoke(main, [str(path), "--emit", "ogma"])
    assert ogma.exit_code == 0 and '"node_v"' in ogma.stdout and '"node"' not in ogma.stdout


def test_keyword_names_are_renamed_inside_definitions_as_in_the_signature(tmp_path):
    """A definition reading ``var``, ``contract``, ``const``, a library node's name or a name
    starting with ``then`` reads the signature's name of each (``var_v`` ...,
    ``v_thenx``: Kind 2 reads ``and then...`` as its operator); a clash takes ``_2``."""
    path = _export(tmp_path, [
        {"variable_name": n, "idType": "Input"} for n in
        ("var", "contract", "const", "H", "delay2", "thenx", "var_v")] + [
        {"variable_name": "returns", "idType": "Internal",
         "assignment": "var and not contract or (const => H) and thenx and var_v"},
        {"variable_name": "k", "idType": "Internal", "dataType": "double",
         "assignment": "if delay2 then 1. else .5 -> pre k"}],
        [{"reqid": "R1", "fulltext": "the c shall always satisfy returns & var & k > 1"}])
    files, skipped, notes = emit_cocospec(_compiled([path]))
    assert skipped == [] and notes == []
    program = _check_structure(files["cSpec"])
    c = program["cSpec"]
    assert [v for v, _t in c.params] == ["var_v", "contract_v", "const_v", "_DQT_H_DQT_", "delay2_v",
                                         "v_thenx", "var_v_2"]
    assert c.locals == [("returns_v", "bool"), ("k", "real")]
    assert ("  var returns_v: bool = ((var_v and (not contract_v)) or (((const_v => "
            "_DQT_H_DQT_) and v_thenx) and var_v_2));") in files["cSpec"]
    assert "  var k: real = (if delay2_v then 1.0 else (0.5 -> (pre k)));" in files["cSpec"]
    trace = [{"var_v": True, "contract_v": False, "const_v": True, "_DQT_H_DQT_": True,
              "delay2_v": t % 2 == 0, "v_thenx": True, "var_v_2": True} for t in range(4)]
    assert lus.run_contract(program, "cSpec", trace)['"R1"'] == [False] * 4


def test_a_line_break_in_an_id_is_folded_in_its_label(tmp_path):
    """An id holding a line break, a quote and ``*)`` is one line in the guarantee's label
    (as every target folds ids), the label's quote escaped: the file holds that guarantee
    only."""
    rid = 'R1\nguarantee "x" false; *) (* \\'
    path = _export(tmp_path, [{"variable_name": "a", "idType": "Input"}],
                   [{"reqid": rid, "fulltext": "the c shall always satisfy a"}])
    files, _skipped, _notes = emit_cocospec(_compiled([path]))
    c = _check_structure(files["cSpec"])["cSpec"]
    assert [(kind, _label_of(label)) for kind, label, _e in c.props] == [
        ("guarantee", one_line(rid))]
    assert '  guarantee "R1 guarantee \\"x\\" false; *) (* \\\\" H(a);' in files["cSpec"]


#: the subset's binding strength of each binary operator (fretc.fretish.lustre's levels)
_LEVEL = {"->": 1, "=>": 2, "or": 3, "xor": 3, "and": 4, "<": 5, "<=": 5, "=": 5, "<>": 5,
          "+": 7, "-": 7, "*": 8}


def _lustre_trees() -> st.SearchStrategy:
    """Boolean Lustre terms of the subset as trees: ``("v", name)``, ``("c", text)``,
    ``(prefix, a)`` for ``not``/``pre``/``-``, ``("if", c, a, b)``, ``(op, a, b)``; over
    booleans ``p``, ``node_`` and numbers ``x``, ``then_``."""
    nums = st.recursive(
        st.one_of(st.sampled_from(["x", "then_"]).map(lambda n: ("v", n)),
                  st.sampled_from(["1.", ".5", "2e0", "3"]).map(lambda c: ("c", c))),
        lambda s: st.one_of(st.tuples(st.sampled_from(["+", "-", "*", "->"]), s, s),
                            st.tuples(st.sampled_from(["-", "pre"]), s)),
        max_leaves=3)
    return st.recursive(
        st.one_of(st.sampled_from(["p", "node_"]).map(lambda n: ("v", n)),
                  st.sampled_from(["true", "false"]).map(lambda c: ("c", c)),
                  st.tuples(st.sampled_from(["<", "<=", "=", "<>"]), nums, nums)),
        lambda b: st.one_of(
            st.tuples(st.sampled_from(["and", "or", "xor", "=>", "=", "<>", "->"]), b, b),
            st.tuples(st.sampled_from(["not", "pre"]), b), st.tuples(st.just("if"), b, b, b)),
        max_leaves=6)


def _tree_text(e, parent: int = 0, right: bool = False) -> str:
    """``e`` as Lustre text, parenthesized only where the subset's precedences need it
    (so the printer must parenthesize what Kind 2 would read otherwise)."""
    op = e[0]
    if op in ("v", "c"):
        return e[1]
    if op in ("not", "pre", "-"):
        a = e[1]
        inner = _tree_text(a, 99)
        return f"{op} {inner}" if a[0] in ("v", "c") else f"{op} ({_tree_text(a)})"
    if op == "if":
        text = f"if {_tree_text(e[1])} then {_tree_text(e[2])} else {_tree_text(e[3])}"
        return f"({text})" if parent else text
    level = _LEVEL[op]
    assoc_right = op in ("->", "=>")
    text = (f"{_tree_text(e[1], level, False)} {op} "
            f"{_tree_text(e[2], level, True)}")
    keep = level < parent or (level == parent and (right != assoc_right or level == 5)) \
        or parent == 99
    return f"({text})" if keep else text


@settings(max_examples=150, deadline=None, derandomize=True)
@given(_lustre_trees(), st.integers(0, 2 ** 32 - 1))
def test_a_printed_definition_means_what_fretc_reads_at_every_tick(tree, seed):
    """Differential: the definition as :func:`print_definition` writes it (names renamed),
    interpreted as Lustre by the tests' reader (Kind 2's precedences), equals fretc's own
    reading of the text (:func:`parse_definition`, expanded and evaluated by the reference
    evaluator) at every tick where Lustre defines it (``pre`` is nil at the first tick,
    which fretc reads as false / 0)."""
    def is_bool(n: str) -> bool:
        return n in ("p", "node_")

    text = _tree_text(tree)
    printed = print_definition(text, is_bool, lambda n: n.rstrip("_") + "_r")
    assert printed.boolean and set(printed.names) <= {"p", "node_", "x", "then_"}
    program = lus.read("contract C(p_r, node_r: bool; x_r, then_r: real) returns ();\n"
                       f"let\n  var d: bool = {printed.text};\n  guarantee \"g\" d;\ntel\n")
    rng = random.Random(seed)
    trace = [{"p": rng.random() < 0.5, "node_": rng.random() < 0.5,
              "x": rng.choice([-1.0, 0.0, 2.5]), "then_": rng.choice([0.0, 3.0])}
             for _ in range(6)]
    inst = lus.Instance(program, program["C"], {
        f"{k.rstrip('_')}_r": (lambda t, k=k: trace[t][k]) for k in trace[0]})
    ours = [inst.value("d", t) for t in range(len(trace))]
    node = Expander("pt", ir.FTP, ir.LAST, free=True).bool(parse_definition(text, is_bool))
    fretc = [bool(v) for v in series(node, trace)]
    assert [v for v in ours if v is not None] == [
        f for v, f in zip(ours, fretc, strict=True) if v is not None], (text, printed.text)
    assert ours[-1] is not None or "pre" in text


def _hostile_files(doc: str, tmp_path_factory) -> tuple[list, dict[str, str], list]:
    path = tmp_path_factory.getbasetemp() / "hostile_cocospec.json"  # (one file: each example)
    path.write_text(doc)
    compiled = _compiled([path])
    files, _skipped, _notes = emit_cocospec(compiled)
    return compiled, files, _notes


@settings(max_examples=80, deadline=None, derandomize=True)
@given(hostile.exports())
def test_hostile_glossaries_write_lustre_that_reads_back(tmp_path_factory, doc):
    """Property over hostile FRET exports (``tests/_hostile_fret.py``: assignments holding
    ``;``, ``tel``, a foreign node and contract, comment openers, quotes, line breaks; names
    that are keywords, library nodes or clash with a renaming; ids holding line breaks and
    quotes): every file reads back by the tests' reader as fretc's library nodes and
    exactly one contract (or comments only when nothing could be written), each name
    declared once and read only where declared, a guarantee per requirement written whose
    label is its id on one line, and every ghost written is one fretc reads."""
    compiled, files, _notes = _hostile_files(doc, tmp_path_factory)
    for stem, text in files.items():
        if "\n-- no contract: " in text:
            assert lus.read(text) == {}
            continue
        program = _check_structure(text)
        c = program[stem]
        written = [c_.id for c_ in compiled if f"  (* {_comment_of(c_.id)}: " in text]
        assert [_label_of(label) for _k, label, _e in c.props] == [
            one_line(rid) for rid in written]
        for ghost, _t in c.locals:
            assert f"  var {ghost}: " in text


def _comment_of(rid: str) -> str:
    return one_line(rid).replace("*)", "* )")


@pytest.mark.usefixtures("shared")
def test_lmcps_tables_are_written_as_their_pre_groups():
    """LMCPS's NN defines ``xt`` as a 199-deep table ``c0 -> pre(c1 -> pre(...))``, past one
    expression's depth: it is written as one ghost per ``pre`` group, and the contract's
    ``xt`` is c0, c1, c2 ... at ticks 0, 1, 2 ..., as FRET's definition."""
    path = ROOT.parent / "shared/corpora/fret_projects/LMCPS/LM_requirements.json"
    files, _skipped, notes = emit_cocospec(_compiled([path]))
    assert not [n for n in notes if "not defined" in n], notes
    program = _check_structure(files["NNSpec"])
    assignment = next(v["assignment"] for v in json.loads(path.read_text())["variables"]
                      if v.get("variable_name") == "xt")
    table = [float(x) for x in re.findall(r"(-?[0-9.]+) *->", assignment)]
    c = program["NNSpec"]
    inst = lus.Instance(program, c, {v: (lambda t: 0.0) for v, _ty in c.params + c.returns})
    assert [inst.value("xt", t) for t in range(6)] == table[:6]
    assert sum(1 for v, _t in c.locals if v.startswith("xt__pre")) == assignment.count("pre(")
