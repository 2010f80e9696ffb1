"""``fretc --emit ogma``: Ogma itself does not install here (a Haskell tool, on neither PyPI
nor Debian), so each file is read back as Ogma's ``fcs`` input format reads it (its JSONPath
queries ``..Internal_variables[*]``, ``..Other_variables[*]``, ``..Requirements[*]``, each
field found exactly once and a string), each requirement's ``ptLTL`` is the pt formula
``fretc FILE --emit ltl --json`` prints, its tokens all in Ogma's SMV grammar, and each
variable's type is the glossary's (FRET's ``bool``/``int``/``real``) or its use's."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from click.testing import CliRunner
from hypothesis import given, settings

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.compiler.cocospec import lustre_type
from fretc.compiler.ogma import emit_ogma
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]

#: the tokens of Ogma's SMV expression grammar (ogma-language-smv, SMV.cf)
_SMV_TOKEN = re.compile(r"\s*(<->|->|<=|>=|!=|[()\[\],!&|<>=+\-*/]|xor|TRUE|FALSE|FTP|LAST"
                        r"|[XGFYZHOSTVU](?![A-Za-z0-9_'])|[0-9]+\.[0-9]+|[0-9]+"
                        r"|[A-Za-z][A-Za-z0-9_']*)")


def _descend(value, key):
    """JSONPath ``..key[*]``: the elements of every ``key`` array anywhere in ``value``,
    and how many such arrays there are."""
    found = []
    if isinstance(value, dict):
        for k, v in value.items():
            if k == key and isinstance(v, list):
                found.append(v)
            else:
                found += _descend(v, key)
    elif isinstance(value, list):
        for v in value:
            found += _descend(v, key)
    return found


def _ogma_reads(text: str) -> dict:
    """What Ogma's ``fcs`` format reads of ``text``: ``{"internal": [...], "external":
    [(name, type)], "requirements": [(name, fretish, ptLTL, CoCoSpecCode)]}``; an
    ``AssertionError`` where Ogma's reader would fail."""
    doc = json.loads(text)
    arrays = {k: _descend(doc, k) for k in ("Internal_variables", "Other_variables",
                                            "Requirements")}
    for k, lists in arrays.items():
        assert len(lists) == 1, k  # one component per file

    def field(obj, key):
        assert isinstance(obj.get(key), str), (key, obj)
        return obj[key]

    return {"internal": arrays["Internal_variables"][0],
            "external": [(field(v, "name"), field(v, "type"))
                         for v in arrays["Other_variables"][0]],
            "requirements": [(field(r, "name"), field(r, "fretish"), field(r, "ptLTL"),
                              field(r, "CoCoSpecCode"))
                             for r in arrays["Requirements"][0]]}


def _smv_tokens_ok(text: str) -> bool:
    i = 0
    while i < len(text.rstrip()):
        m = _SMV_TOKEN.match(text, i)
        if m is None:
            return False
        i = m.end()
    return True


def _ltl_pt(paths) -> dict:
    r = CliRunner().invoke(main, [str(p) for p in paths] + ["--emit", "ltl", "--json"])
    return {x["id"]: x.get("pt") for x in json.loads(r.stdout)}


def _compiled(paths):
    return compile_entries(load_requirements([str(x) for x in paths]))


def test_safe_ros_components_as_ogma_reads_them():
    paths = [ROOT / "requirements/safe_ros.fret", ROOT / "requirements/r1.fret"]
    files, skipped, notes = emit_ogma(_compiled(paths))
    assert skipped == [] and notes == []
    assert sorted(files) == ["agilex_agentSpec", "cmd_vel_interceptorSpec",
                             "safety_systemSpec", "scout_miniSpec"]
    pts = _ltl_pt(paths)
    seen = set()
    for stem, text in files.items():
        assert list(json.loads(text)) == [stem]
        got = _ogma_reads(text)
        assert got["internal"] == []
        for name, _fretish, pt, coco in got["requirements"]:
            assert pt == pts[name] and _smv_tokens_ok(pt), (name, pt)
            assert coco.startswith("H(") or coco.startswith("(H(")
            seen.add(name)
        if stem == "scout_miniSpec":
            assert got["external"] == [("linear_speed", "real"), ("angular_speed", "real"),
                                       ("clearance", "real")]
        if stem == "agilex_agentSpec":
            assert got["external"] == [("too_close", "bool"), ("stopped", "bool")]
    assert seen == set(pts)


def test_what_ogma_cannot_read_is_left_out_with_the_reason(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text("@inputs a, n\n@outputs b\nA1: the c shall always satisfy b | a\n"
                   "A2: the c shall always satisfy absReal(n) > 3\n"
                   "A3: the c shall always satisfy n mod 2 = 1\n")
    r = CliRunner().invoke(main, [str(src), "--emit", "ogma"])
    assert r.exit_code == 0, r.output
    assert "skipped A2 (cSpec.json): Ogma's SMV grammar has no function (absReal)" in r.output
    assert "skipped A3 (cSpec.json): Ogma's SMV grammar has no mod operator" in r.output
    got = _ogma_reads(r.stdout)
    assert [x[0] for x in got["requirements"]] == ["A1"]
    assert got["external"] == [("a", "bool"), ("n", "real"), ("b", "bool")]


def test_the_cli_writes_json_files_and_refuses_an_output_over_an_input(tmp_path):
    runner = CliRunner()
    out = tmp_path / "o"
    r = runner.invoke(main, ["requirements/safe_ros.fret", "--emit", "ogma", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert (out / "scout_miniSpec.json").is_file()
    before = (out / "scout_miniSpec.json").read_bytes()
    runner.invoke(main, ["requirements/safe_ros.fret", "--emit", "ogma", "-o", str(out)])
    assert (out / "scout_miniSpec.json").read_bytes() == before
    r = runner.invoke(main, ["requirements/safe_ros.fret", "--emit", "ogma", "-o",
                             str(tmp_path / "x.json")])
    assert r.exit_code == 2  # several components: -o FILE.json is refused
    assert "4 files are written (one per component: agilex_agentSpec, " in r.output
    src = tmp_path / "cSpec.json"
    src.write_text(json.dumps([{"reqid": "A", "fulltext": "the c shall always satisfy b"}]))
    r = runner.invoke(main, [str(src), "--emit", "ogma", "-o", str(tmp_path)])
    assert r.exit_code == 2 and json.loads(src.read_text())[0]["reqid"] == "A"


def test_fret_case_studies_as_ogma_reads_them(shared):
    """Every component of FRET's case studies: the file reads as Ogma reads it, each
    ptLTL is fretc's pt formula and in Ogma's SMV tokens, each declared Input and Output
    has the glossary's type as FRET's export maps it."""
    checked = 0
    for path in sorted((shared / "corpora/fret_projects").glob("*/*.json")):
        data = json.loads(path.read_text())
        glossary = {(v["component_name"], v["variable_name"]): v.get("dataType", "")
                    for v in data.get("variables", []) if isinstance(v, dict)
                    and "variable_name" in v and v.get("idType") in ("Input", "Output")}
        files, _skipped, _notes = emit_ogma(_compiled([path]))
        pts = _ltl_pt([path])
        for stem, text in files.items():
            got = _ogma_reads(text)
            component = stem[:-len("Spec")]
            for name, typ in got["external"]:
                declared = glossary.get((component, name))
                if declared:
                    assert typ == lustre_type(declared), (stem, name, declared, typ)
            for name, _text, pt, _coco in got["requirements"]:
                assert pt == pts[name] and _smv_tokens_ok(pt), (path.name, name)
                checked += 1
    assert checked >= 150, checked


def test_numbers_and_names_outside_ogmas_tokens_are_left_out(tmp_path):
    src = tmp_path / "r.fret"
    src.write_text('R1: the c shall always satisfy x > 1e3\n'
                   'R2: the c shall always satisfy "last" & b\n'
                   'R3: the c shall always satisfy x > 2.5\n')
    files, skipped, _notes = emit_ogma(_compiled([src]))
    assert [(rid, why.split(" (")[0]) for _s, rid, why in skipped] == [
        ("R1", "Ogma's SMV grammar has no literal 1e3"),
        ("R2", "the name _DQT_last_DQT_ is no identifier of Ogma's SMV grammar")]
    got = _ogma_reads(files["cSpec"])
    assert [r[0] for r in got["requirements"]] == ["R3"]


# ---------------------------------------------------------------- names, hostile glossaries
sys.path.insert(0, str(ROOT / "tests"))
import _hostile_fret as hostile  # noqa: E402
import _lustre_subset as lus  # noqa: E402

from fretc.common.textsafe import one_line  # noqa: E402

#: the words of Ogma's SMV grammar that are no variable
_SMV_WORDS = frozenset("X G F Y Z H O S T V U TRUE FALSE FTP LAST xor".split())


def _smv_names(pt: str) -> set[str]:
    return {w for w in re.findall(r"[A-Za-z_][A-Za-z0-9_']*", pt) if w not in _SMV_WORDS}


def _lustre_names(code: str) -> set[str]:
    """The variables a CoCoSpecCode expression reads (names not called)."""
    toks = lus.tokens(code)
    return {w for i, (kind, w) in enumerate(toks) if kind == "id"
            and (i + 1 == len(toks) or toks[i + 1][1] != "(")}


def _check_names(text: str) -> dict:
    """Ogma reads the file; ``Other_variables`` names each variable once, and every name
    each requirement's ``ptLTL`` and ``CoCoSpecCode`` read is one of them (and both read the
    same); each requirement's name is one line."""
    got = _ogma_reads(text)
    names = [n for n, _t in got["external"]]
    assert len(names) == len(set(names)), names
    for rid, _fretish, pt, coco in got["requirements"]:
        assert "\n" not in rid and rid == one_line(rid)
        assert _smv_tokens_ok(pt), pt
        assert _smv_names(pt) <= set(names), (rid, pt, names)
        if coco:
            assert _lustre_names(coco) == _smv_names(pt), (rid, pt, coco)
    return got


def test_ogma_names_are_the_contracts_in_every_field(tmp_path):
    """Variables named ``node``, ``let``, ``tel`` (and a clash with a renaming, ``let_v``):
    ``Other_variables``, ``ptLTL`` and ``CoCoSpecCode`` all read ``node_v``, ``let_v``,
    ``tel_v``, ``let_v_2``; an id holding a line break is one line."""
    path = tmp_path / "p.json"
    path.write_text(json.dumps({
        "requirements": [{"reqid": "R1\nR2", "fulltext": "the c shall always satisfy node & "
                          "(let_v | tel) & k"}],
        "variables": [{"variable_name": n, "component_name": "c", "idType": kind,
                       "dataType": "boolean", "assignment": text}
                      for n, kind, text in [("node", "Input", ""), ("let", "Input", ""),
                                            ("tel", "Output", ""),
                                            ("k", "Internal", "node and not let")]]}))
    files, skipped, notes = emit_ogma(_compiled([path]))
    assert skipped == []
    got = _check_names(files["cSpec"])
    assert got["external"] == [("node_v", "bool"), ("let_v", "bool"), ("tel_v", "bool"),
                               ("let_v_2", "bool"), ("k", "bool")]
    [(rid, _text, pt, coco)] = got["requirements"]
    assert rid == "R1 R2"
    assert pt == "(H ((node_v & (let_v_2 | tel_v)) & k))"
    assert coco == "H(((node_v and (let_v_2 or tel_v)) and k))"
    assert notes == ["cSpec: k (a FRET Internal variable) is an Other_variables entry: the "
                     "monitor reads it as an input"]


@settings(max_examples=60, deadline=None, derandomize=True)
@given(hostile.exports())
def test_hostile_glossaries_give_ogma_the_names_its_expressions_read(tmp_path_factory, doc):
    """Property over the hostile FRET exports of ``tests/_hostile_fret.py`` (keywords,
    library nodes and renamings as names; hostile assignments and ids): every file reads as
    Ogma reads it, its ``Other_variables`` name each variable once, and each requirement's
    ``ptLTL`` and ``CoCoSpecCode`` read those names and the same ones."""
    path = tmp_path_factory.getbasetemp() / "hostile_ogma.json"  # (one file: each example)
    path.write_text(doc)
    files, _skipped, _notes = emit_ogma(_compiled([path]))
    for text in files.values():
        _check_names(text)
