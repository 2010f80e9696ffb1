"""The constraints file of the qualified dependency set
(src/fretc/qualification/constraints.txt) pins every runtime dependency of fretc (and those
of its dependencies when it was written), one ``name==version`` a line: regenerate it (``python -m
fretc.qualification.constraints``) when a dependency is added or removed."""

from __future__ import annotations

import re

from fretc.qualification.constraints import FILE, closure, text


def test_the_shipped_constraints_pin_the_dependency_closure():
    lines = [ln for ln in FILE.read_text(encoding="utf-8").splitlines()
             if ln and not ln.startswith("#")]
    pins = dict(ln.split("==") for ln in lines)
    assert all(re.fullmatch(r"[a-z0-9-]+==[^=\s]+", ln) for ln in lines)
    # every dependency fretc declares is pinned (a newer release of one may bring another
    # transitive dependency: the file is written again when the qualified set changes)
    from importlib import metadata

    from fretc.qualification.constraints import _name

    direct = {n for line in metadata.distribution("fretc").requires or []
              if (n := _name(line)) is not None}
    assert direct <= set(pins), direct - set(pins)
    assert direct <= set(closure()) and "click" in pins and "lark" in pins


def test_the_file_is_written_sorted_with_its_header():
    out = text({"a": "1.0", "b-c": "2"})
    assert out.splitlines()[2:] == ["a==1.0", "b-c==2"] and out.startswith("#")
