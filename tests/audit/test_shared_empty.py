"""The shared empty evidence containers of :data:`fretc.audit.verdict.NO_EVIDENCE`: every way
a dict or list changes in place raises TypeError (a change would be every sharer's); reading,
JSON, equality, copies and pickles behave as an empty ``{}`` or ``[]``, and copies are plain
containers that can change."""

from __future__ import annotations

import copy
import dataclasses
import json
import pickle

import pytest

from fretc.audit.verdict import NO_EVIDENCE, SharedEmptyDict, SharedEmptyList, Verdict

CHANGES_D = [lambda d: d.__setitem__("a", 1), lambda d: d.update(a=1),
             lambda d: d.setdefault("a", 1), lambda d: d.pop("a", None), lambda d: d.popitem(),
             lambda d: d.clear(), lambda d: d.__ior__({"a": 1}), lambda d: d.__delitem__("a")]
CHANGES_L = [lambda x: x.append(1), lambda x: x.extend([1]), lambda x: x.insert(0, 1),
             lambda x: x.remove(1), lambda x: x.pop(), lambda x: x.clear(), lambda x: x.sort(),
             lambda x: x.reverse(), lambda x: x.__setitem__(slice(0, 0), [1]),
             lambda x: x.__delitem__(slice(0, 1)), lambda x: x.__iadd__([1]),
             lambda x: x.__imul__(2)]


@pytest.mark.parametrize("change", CHANGES_D)
def test_a_shared_empty_dict_refuses_every_change(change):
    d = SharedEmptyDict()
    with pytest.raises(TypeError):
        change(d)
    assert d == {} and len(d) == 0


@pytest.mark.parametrize("change", CHANGES_L)
def test_a_shared_empty_list_refuses_every_change(change):
    x = SharedEmptyList()
    with pytest.raises(TypeError):
        change(x)
    assert x == [] and len(x) == 0


def test_a_verdict_without_evidence_reads_writes_and_copies_as_one_with_its_own():
    shared = Verdict("l.mcap", "R[e=1]", verdict="satisfied", **NO_EVIDENCE)
    own = Verdict("l.mcap", "R[e=1]", verdict="satisfied")
    assert shared == own
    assert json.dumps(shared.to_json(0)) == json.dumps(own.to_json(0))
    for c in (copy.copy(shared.values), copy.deepcopy(shared.values),
              pickle.loads(pickle.dumps(shared.values))):
        assert type(c) is dict
        c["a"] = 1
    for c in (copy.copy(shared.margin), copy.deepcopy(shared.margin),
              pickle.loads(pickle.dumps(shared.margin))):
        assert type(c) is list
        c.append(1)
    back = pickle.loads(pickle.dumps(shared))
    assert back == own and type(back.values) is dict and type(back.waiting_for) is list
    assert dataclasses.asdict(shared) == dataclasses.asdict(own)
    assert shared.values == {} and shared.margin == [] and (shared.margin + [1]) == [1]
    assert set(NO_EVIDENCE) == {f.name for f in dataclasses.fields(Verdict)
                                if f.default_factory in (dict, list) and f.name != "notes"}


def _types(x):
    """Every container type in a JSON-like document."""
    if isinstance(x, dict):
        yield type(x)
        for v in x.values():
            yield from _types(v)
    elif isinstance(x, (list, tuple)):
        yield type(x)
        for v in x:
            yield from _types(v)


def test_a_verdicts_json_holds_plain_containers_only():
    """The document of a verdict without evidence is plain data: PyYAML's safe dumper (which
    refuses a subclass of dict or list) writes it as it writes the same verdict's with
    containers of its own."""
    import yaml

    shared = Verdict("l.mcap", "R[e=1]", verdict="satisfied", **NO_EVIDENCE).to_json(0)
    own = Verdict("l.mcap", "R[e=1]", verdict="satisfied").to_json(0)
    assert set(_types(shared)) <= {dict, list}
    assert yaml.safe_dump(shared) == yaml.safe_dump(own)
