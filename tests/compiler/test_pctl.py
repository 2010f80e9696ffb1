"""FRET 3.1's probabilistic form (compiler/pctl.py) against FRET's own output
(../shared/fretish/fret_probabilistic_vectors.jsonl, 45 sentences): the five-part key, the
number, operators and places of the bounds, and the path formula (bounds removed) equal to
ft_inf by Spot; FRET's own PCTL contradicts FRET's LTL in 19 sentences, in the four template
families docs/reference/semantics.md lists, each shown by a trace; and a sweep of all 576
five-part keys for the structure."""

from __future__ import annotations

import itertools
import json

import pytest
from click.testing import CliRunner

import _pctl
from _shared import jsonl, needs_shared
from fretc.cli import main
from fretc.compiler.pctl import pctl_key, pctl_of, prism_text, strip_bounds
from fretc.compiler.semantics import formalize
from fretc.common.errors import FretishError
from fretc.fretish.parser import parse

VECTORS = jsonl("fretish/fret_probabilistic_vectors.jsonl")
ACCEPTED = [v for v in VECTORS if not v.get("parse_errors")]


def _spot(*trees):
    """Spot formulas of the trees (bounds removed), large time bounds renamed alike."""
    import spot
    big: dict = {}
    return [spot.formula(_pctl.spot_text(t, big)) for t in trees]


@needs_shared
@pytest.mark.tor("TOR-SEM-011")
def test_45_vectors_keys_and_refusals_as_fret():
    assert len(VECTORS) == 45
    for v in VECTORS:
        if v.get("parse_errors"):
            with pytest.raises(FretishError):
                parse(v["text"])
            continue
        form = pctl_of(parse(v["text"]))
        assert form.key == v["key"] == v["key_pctl"], v["id"]
    assert len(ACCEPTED) == 41  # E5's '!=' is accepted, as FRET accepts it


@needs_shared
@pytest.mark.parametrize("v", ACCEPTED, ids=[v["id"] for v in ACCEPTED])
@pytest.mark.tor("TOR-SEM-011")
def test_bounds_where_fret_puts_them_and_path_is_ft_inf(v):
    req = parse(v["text"])
    form = pctl_of(req)
    ours = [(b["bound"], b["parent"], tuple(b["under"])) for b in form.bounds]
    theirs = _pctl.bounds(_pctl.read(v["pctl"]))
    assert ours == theirs == _pctl.bounds(_pctl.read(v["pctlExpanded"]))
    assert strip_bounds(form.tree) == formalize(req).ft_inf  # by construction, exactly
    # the printed PCTL read back, bounds removed, against fretc's and FRET's ft_inf (Spot)
    path, fretc_inf, fret_inf = _spot(_pctl.read(form.text), _pctl.read(prism_text(
        formalize(req).ft_inf)), _pctl.read(v["ft_inf"]))
    assert _pctl.equivalent(path, fretc_inf) and _pctl.equivalent(path, fret_inf)


#: FRET's PCTL against FRET's LTL: the sentences whose PCTL path (bounds removed) is not
#: ft_inf, by template family (docs/reference/semantics.md, "FRET's probabilistic templates")
FAMILIES = {
    "one-point interval vacuous": ["P17", "P19", "P20", "P21", "P22", "P23", "P25"],
    "timed response past the scope's end": ["P18", "P21", "P24", "P32"],
    "before scope off by one point": ["P31", "P33", "P34"],
    "only scopes' response not negated": ["P35", "P36", "P37", "P38", "P39", "P40"],
}
#: per family a sentence and a lasso (Spot's word syntax) on which FRET's PCTL path and
#: FRET's ft_inf disagree: (vector, word, ft_inf holds, FRET's PCTL path holds)
SEPARATING = [
    ("P17", 'cruise & !"speed <= 2.0"; cycle{!cruise}', False, True),
    ("P18", "contact & docking & !latched; docking & !latched; cycle{!docking & !latched}",
     True, False),
    ("P31", "!armed & !landing; cycle{landing}", False, True),
    ("P31", "cycle{landing & !armed}", True, False),
    ("P35", "cycle{!auto & autonomous}", False, True),
]


@needs_shared
def test_fret_pctl_contradicts_fret_ltl_in_19_sentences_by_family():
    differ = []
    for v in ACCEPTED:
        path, inf = _spot(_pctl.read(v["pctlExpanded"]), _pctl.read(v["ft_inf"]))
        if not _pctl.equivalent(path, inf):
            differ.append(v["id"])
    assert len(differ) == 19
    assert sorted(differ) == sorted(set(itertools.chain(*FAMILIES.values())))


@needs_shared
@pytest.mark.parametrize("vid,word,ltl,fret_pctl", SEPARATING)
def test_a_trace_separates_each_family(vid, word, ltl, fret_pctl):
    import spot
    v = next(x for x in ACCEPTED if x["id"] == vid)
    form = pctl_of(parse(v["text"]))
    path, inf, fret = _spot(_pctl.read(form.text), _pctl.read(v["ft_inf"]),
                            _pctl.read(v["pctlExpanded"]))
    w = spot.parse_word(word).as_automaton()

    def holds(f) -> bool:
        return spot.translate(f).intersects(w)

    assert holds(inf) is ltl and holds(path) is ltl  # fretc's path: FRET's LTL
    assert holds(fret) is fret_pctl


# ------------------------------------------------------------------ all 576 keys
SCOPES = {"null": "", "in": "in mode m ", "notin": "unless in mode m ",
          "onlyIn": "only in mode m ", "after": "after m ", "before": "before m ",
          "onlyAfter": "only after m ", "onlyBefore": "only before m "}
CONDITIONS = {"null": "", "regular": "upon c ", "holding": "whenever c "}
TIMINGS = {"immediately": "immediately ", "next": "at the next timepoint ",
           "finally": "finally ", "eventually": "eventually ", "null": "",
           "always": "always ", "never": "never ", "within": "within 2 ticks ",
           "for": "for 2 ticks ", "after": "after 2 ticks ", "until": "until s ",
           "before": "before s "}
KEYS = list(itertools.product(SCOPES, CONDITIONS, ("bound", "null"), TIMINGS))


def _sentence(scope, cond, prob, timing) -> str:
    p = "with probability >= 0.9 " if prob == "bound" else ""
    return f"{SCOPES[scope]}{CONDITIONS[cond]}the robot shall {p}{TIMINGS[timing]}satisfy r"


def _unders_by_pair() -> dict:
    """(scope, condition) -> the bounds' places in FRET's vectors (timing-independent)."""
    out: dict = {}
    for v in ACCEPTED:
        scope, cond = v["key"].split(",")[:2]
        shape = [(b[1], b[2]) for b in _pctl.bounds(_pctl.read(v["pctl"]))]
        assert out.setdefault((scope, cond), shape) == shape, v["id"]
    return out


@pytest.mark.tor("TOR-SEM-011")
def test_all_576_keys_have_fret_bound_structure():
    assert len(KEYS) == 576
    fret = _unders_by_pair() if ACCEPTED else {}
    for scope, cond, prob, timing in KEYS:
        req = parse(_sentence(scope, cond, prob, timing))
        form = pctl_of(req)
        assert form.key == ",".join((scope, cond, prob, timing, "satisfaction"))
        assert form.key == pctl_key(req.key, prob == "bound")
        assert strip_bounds(form.tree) == formalize(req).ft_inf, form.key
        inner = form.bounds[1:] if (scope, cond) != ("null", "null") else form.bounds
        # FRET's templates: one bound per place the obligation sits (2 in scopes checked at
        # their start and later, 2 for a regular condition), the whole under P>=1
        want = (2 if scope in ("in", "notin", "onlyIn", "onlyBefore") else 1) * (
            2 if cond == "regular" else 1)
        assert len(inner) == want, form.key
        assert all(b["bound"] == ("P>=0.9" if prob == "bound" else "P>=1") for b in inner)
        outer = None if (scope, cond) == ("null", "null") else 0
        assert all(b["parent"] == outer for b in inner)
        if (scope, cond) in fret:
            assert [(b["parent"], tuple(b["under"])) for b in form.bounds] == fret[(scope, cond)]


# ------------------------------------------------------------------ the commands
def test_emit_ltl_prints_fret_keys_and_pctl(tmp_path):
    f = tmp_path / "p.fret"
    f.write_text("P2: upon too_close the robot shall, with probability >= 0.9, within 1 tick "
                 "satisfy stopped\nQ: the robot shall always satisfy ok\n")
    out = CliRunner().invoke(main, [str(f), "--emit", "ltl"]).output
    assert "  key     null,regular,bound,within,satisfaction\n" in out
    assert "  key_ltl null,regular,within,satisfaction\n" in out
    assert ("  pctl    P>=1 [ ((G (((! too_close) & (X too_close)) => (X (P>=0.9 [ (F<=1 "
            "stopped) ])))) & (too_close => (P>=0.9 [ (F<=1 stopped) ]))) ]") in out
    assert "  key     null,null,always,satisfaction\n" in out  # no probability: as before
    doc = json.loads(CliRunner().invoke(main, [str(f), "--emit", "ltl", "--json"]).output)
    assert doc[0]["key"] == "null,regular,bound,within,satisfaction"
    assert doc[0]["key_ltl"] == "null,regular,within,satisfaction"
    assert [b["bound"] for b in doc[0]["pctl_bounds"]] == ["P>=1", "P>=0.9", "P>=0.9"]
    assert doc[0]["pctl_bounds"][1]["under"] == ["G", "X"]
    assert "key_ltl" not in doc[1] and doc[1]["key"] == "null,null,always,satisfaction"


def test_emit_prism_writes_a_properties_file(tmp_path):
    f = tmp_path / "p.fret"
    f.write_text("P2: upon c the robot shall, with probability >= 0.9, within 1 tick satisfy "
                 "r\nQ: the robot shall always satisfy ok\n"
                 "E: the robot shall with probability = 0.5 eventually satisfy ok\n"
                 "N: the robot shall with probability != 1 eventually satisfy ok\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "prism", "-o", str(tmp_path / "p.props")])
    assert res.exit_code == 0, res.output
    text = (tmp_path / "p.props").read_text()
    assert ('"P2": P>=1 [ ((G (((! c) & (X c)) => (X (P>=0.9 [ (F<=1 r) ])))) & (c => '
            '(P>=0.9 [ (F<=1 r) ]))) ];') in text
    assert '"Q": P>=1 [ (G ok) ];' in text  # no probability: FRET's null probability
    assert '"E": ((P>=0.5 [ (F ok) ]) & (P<=0.5 [ (F ok) ]));' in text  # PRISM has no '='
    assert '"N": P<1 [ (F ok) ];' in text
    assert "// P2 (" in text and "with probability >= 0.9" in text


def test_emit_prism_expands_fret_functions_or_refuses_them(tmp_path):
    """FRET's functions were written as FRET prints them (``persisted(3,a)``,
    ``preBool(FALSE,a)``, ``absReal(x)``): PRISM cannot parse them. abs/min/max are PRISM's
    built-in ``max``/``min``; past-time functions and functions PRISM has not are refused,
    the requirement named on stderr and in a comment, never written as a property."""
    f = tmp_path / "p.fret"
    f.write_text("C: the sw shall with probability > 0.5 always satisfy minReal(x, y) > 1 & "
                 "maxInt(x, y) < 3 & absReal(x) < 4 & absInt(y) > 0\n"
                 "B: the sw shall with probability >= 0.9 always satisfy persisted(3, a)\n"
                 "D: the sw shall with probability >= 0.9 always satisfy preBool(false, a)\n"
                 "U: the sw shall with probability >= 0.9 always satisfy det(x, y) > 0\n"
                 "P: the sw shall with probability >= 0.9 always satisfy preInt(0, x) <= y\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "prism", "-o", str(tmp_path / "p.props")])
    assert res.exit_code == 0, res.output
    text = (tmp_path / "p.props").read_text()
    assert ('"C": P>0.5 [ (G ((((min(x, y) > 1) & (max(x, y) < 3)) & (max(x, (- x)) < 4)) & '
            '(max(y, (- y)) > 0))) ];') in text, text
    props = [line for line in text.splitlines() if not line.startswith("//")]
    assert len(props) == 1 and not any(w in text.split("//")[0] for w in ("Real(", "Int("))
    for rid in ("B", "D", "U", "P"):
        assert f"skipped {rid} (p.props): " in res.output, res.output
    assert text.count("//   not in PRISM: ") == 4
    # each named as what it is: a past-time function by its call, a comparison reading a
    # previous value as a comparison (it was called a function)
    assert "the past-time function preBool(FALSE,a) has no form" in res.output, res.output
    assert ("the comparison (preInt(0,x) <= y), which reads a previous tick's value, has no "
            "form") in res.output, res.output


@pytest.mark.parametrize("bound,ok", [("< 0", False), ("< 1e-400", False), ("<= 1e-400", True),
                                      ("> 1", False), ("> 0.99999999999999999999", False),
                                      ("< 1e-300", True)])
def test_a_probability_that_is_0_or_1_as_a_double_is_judged_as_it(tmp_path, bound, ok):
    """``< 0`` was refused while ``< 1e-400`` (0 as a double: what the monitors, the
    statistics and PRISM read) was accepted and written ``P<1e-400``."""
    f = tmp_path / "p.fret"
    f.write_text(f"A: the sw shall with probability {bound} always satisfy p\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "prism"])
    assert (res.exit_code == 0) == ok, res.output
    if not ok:
        assert "is no probability bound" in res.output
