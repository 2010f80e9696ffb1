"""Verdicts rolled up to parent requirements (:mod:`fretc.reports.rollup`): against a brute-force
reading of its rule on random requirement trees (hypothesis), and on the Safe-ROS tree (SR-0
above R1..R6, R1 above R2) in the matrix, the report and every export."""

from __future__ import annotations

import json

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.reports.rollup import NOT_IN_AUDIT, ROLLUP_ORDER, children_of, parents_of, rollups

OWN = ("satisfied", "vacuous", "violated", "unknown", "error", "not formalized")


def _doc(parents: dict[str, list[str]], own: dict[str, str]) -> dict:
    reqs = [{"id": r, "origin": {"parents": ps}} for r, ps in parents.items()
            if own[r] != "not formalized"]
    items = [{"id": r, "origin": {"parents": ps}} for r, ps in parents.items()
             if own[r] == "not formalized"]
    return {"requirements": reqs, "not_formalized": items}


def _expected(rid: str, children: dict, own: dict) -> str:
    """The rule of the module docstring, by brute force over the descendants."""
    below, stack = {rid}, [rid]
    while stack:
        for c in children.get(stack.pop(), ()):
            if c not in below:
                below.add(c)
                stack.append(c)
    words = set()
    for x in below:
        o = own.get(x, NOT_IN_AUDIT)
        if o in ("satisfied", "vacuous", "violated"):
            words.add(o)
        elif o in ("unknown", "error"):
            words.add("unverified")
        elif not children.get(x):  # not formalized / absent leaf: nothing verifies it
            words.add("unverified")
    return min(words, key=ROLLUP_ORDER.index)


@st.composite
def _trees(draw):
    n = draw(st.integers(1, 9))
    ids = [f"R{i}" for i in range(n)]
    parents = {r: draw(st.lists(st.sampled_from(ids + ["TOP"]), max_size=2, unique=True))
               for r in ids}
    own = {r: draw(st.sampled_from(OWN)) for r in ids}
    return parents, own


@settings(max_examples=200, deadline=None)
@given(_trees())
def test_rollup_follows_its_rule_on_random_trees_with_cycles(tree):
    parents, own = tree
    doc = _doc(parents, own)
    got = rollups(doc, own)
    children = children_of(parents_of(doc))
    assert set(got) == set(children)
    for rid, ru in got.items():
        assert ru.own == own.get(rid, NOT_IN_AUDIT)
        if ru.verdict in ("violated", "unverified"):
            # the path goes down the links to a requirement whose own verdict decides
            assert ru.path[0] == rid
            for a, b in zip(ru.path, ru.path[1:]):
                assert b in children[a]
            last = own.get(ru.path[-1], NOT_IN_AUDIT)
            assert ru.decided_by == last
            assert (last == "violated") == (ru.verdict == "violated")
        else:
            assert ru.path == () and ru.decided_by == ""
        if _acyclic(children):
            assert ru.verdict == _expected(rid, children, own), (rid, parents, own)


def _acyclic(children: dict) -> bool:
    state: dict = {}

    def visit(x) -> bool:
        if state.get(x) == 1:
            return False
        if state.get(x) == 2:
            return True
        state[x] = 1
        ok = all(visit(c) for c in children.get(x, ()))
        state[x] = 2
        return ok
    return all(visit(x) for x in list(children))


def test_a_parent_is_unverified_by_a_child_without_verdict_and_absent_parents_count():
    parents = {"A": ["TOP"], "B": ["TOP"], "C": ["A"], "D": ["A"]}
    own = {"A": "not formalized", "B": "satisfied", "C": "vacuous", "D": "unknown"}
    got = rollups(_doc(parents, own), own)
    assert got["A"].verdict == "unverified" and got["A"].path == ("A", "D")
    assert got["TOP"].own == NOT_IN_AUDIT and got["TOP"].verdict == "unverified"
    assert got["TOP"].text() == "unverified via TOP > A > D (D unknown)"
    own["D"] = "violated"
    assert rollups(_doc(parents, own), own)["TOP"].text() == \
        "violated via TOP > A > D (D violated)"
    own["D"] = "vacuous"
    assert rollups(_doc(parents, own), own)["TOP"].verdict == "satisfied"  # B satisfied
    own["B"] = "vacuous"
    assert rollups(_doc(parents, own), own)["TOP"].verdict == "vacuous"


def test_fret_parent_lines_are_links_when_there_is_no_origin():
    doc = {"requirements": [{"id": "R1", "parent": None}, {"id": "R2", "parent": "R1"}]}
    got = rollups(doc, {"R1": "satisfied", "R2": "violated"})
    assert list(got) == ["R1"] and got["R1"].text() == "violated via R1 > R2 (R2 violated)"


def test_safe_ros_tree_in_matrix_and_exports(tmp_path):
    from fretc.reports.export_results import requirement_results
    from fretc.reports.matrix import matrix_rows

    own = {"R1": "satisfied", "R2": "violated", "R3": "satisfied", "SR-0": "not formalized"}
    parents = {"R1": ["SR-0"], "R2": ["R1"], "R3": ["SR-0"], "SR-0": []}
    doc = _doc(parents, own)
    for r in doc["requirements"]:
        r.update(text="the sw shall always satisfy p")
    doc["logs"] = [{"log": "a.mcap", "verdicts": [{"requirement": r, "verdict": v}
                                                  for r, v in own.items()
                                                  if v != "not formalized"]}]
    res = requirement_results(json.loads(json.dumps(doc)), "id", "date")
    assert res["SR-0"].rollup == "violated"
    assert res["SR-0"].rollup_path == "violated via SR-0 > R1 > R2 (R2 violated)"
    assert res["R2"].rollup is None                  # not a parent
    rows = {r.requirement: r for r in matrix_rows(doc)}
    assert rows["R2"].parents == "R1" and rows["R2"].rolled_up == ""
    assert rows["SR-0"].rolled_up.startswith("violated via SR-0 > R1 > R2")
