"""The checked-in template table (compiler/table/, compiler.template_table): it is exactly
what ``python -m fretc.compiler.make_table`` writes from compiler.semantics today, one file per
template key; a key without a file takes the full build. (That the filled-in templates
print what the full build prints: tests/compiler/test_instantiate.py.)"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fretc.compiler import instantiate as I
from fretc.compiler import template_table as TT
from fretc.compiler.printers import to_smv, to_spot
from fretc.compiler.semantics import formalize
from fretc.fretish import parse

ROOT = Path(__file__).resolve().parents[2]
REGENERATE = "python -m fretc.compiler.make_table"


def test_checked_in_table_is_what_make_table_writes(tmp_path):
    """A change to the construction (compiler/semantics.py and the modules it uses) that
    forgets to regenerate the table fails here."""
    out = tmp_path / "table"
    subprocess.run([sys.executable, "-m", "fretc.compiler.make_table", "--out", str(out)],
                   cwd=ROOT, check=True, capture_output=True)
    made = sorted(os.listdir(out))
    checked_in = sorted(os.listdir(TT.TABLE_DIR))
    assert made == checked_in, (
        f"compiler/table/ has other files than the generator writes; run `{REGENERATE}` "
        "and commit compiler/table/")
    stale = [name for name in made if (out / name).read_bytes()
             != (Path(TT.TABLE_DIR) / name).read_bytes()]
    assert not stale, (f"{len(stale)} template files differ from what compiler/semantics.py "
                       f"gives now (e.g. {stale[0]}); run `{REGENERATE}` and commit "
                       "compiler/table/")


def test_one_file_per_key_with_sorted_keys():
    assert len(TT.ALL_KEYS) == len(set(map(TT.file_name, TT.ALL_KEYS))) == 432
    for key in TT.ALL_KEYS[::23]:
        text = (Path(TT.TABLE_DIR) / TT.file_name(key)).read_text(encoding="utf-8")
        data = json.loads(text)
        assert list(data) == sorted(data) == ["fallback", "ft", "ft_inf", "ft_inf_spot",
                                              "ft_spot", "key", "pt"]
        scope, cond, timing, n = key
        assert data["key"] == [scope, cond, timing, "n" if n == -1 else n]


def test_fields_are_atoms_of_their_formula_and_bounds():
    """ft's texts name ft's atoms (fields 0-3), ft_inf's ft_inf's (4-7), pt's pt's (8-11);
    any form may name the bounds (12-17); a key without a duration names none."""
    for key in TT.ALL_KEYS:
        t = TT.template(*key[:3], 5 if key[3] == -1 else key[3])
        allowed = {"ft": range(0, 4), "ft_inf": range(4, 8), "pt": range(8, 12),
                   "ft_spot": range(0, 4), "ft_inf_spot": range(4, 8)}
        for name, form in zip(TT.FORM_NAMES, t.forms):
            if form is None:
                continue
            for f in form[1]:
                assert f in allowed[name] or (key[3] is not None and TT.BOUND0 <= f < 18)


def _texts(f) -> list:
    return [I.formula_text(f, w) for w in ("ft", "ft_inf", "pt", "ft_spot", "ft_inf_spot")]


@pytest.mark.parametrize("text", [
    "in m upon p the sw shall within 3 ticks satisfy q",
    "the sw shall always satisfy persisted(2, q) & r",
])
def test_a_key_without_a_file_takes_the_full_build(text, tmp_path, monkeypatch):
    monkeypatch.setattr(TT, "TABLE_DIR", str(tmp_path))
    monkeypatch.setattr(TT, "_TEMPLATES", {})
    f = I.instantiate(parse(text))
    assert not isinstance(f, I.InstantiatedFormalization)
    full = formalize(parse(text))
    assert _texts(f) == [to_smv(full.ft), to_smv(full.ft_inf), to_smv(full.pt, ftp="(Z FALSE)"),
                         to_spot(full.ft), to_spot(full.ft_inf)]


def test_a_key_is_read_once():
    """The file of a key is read on its first use and the template kept."""
    a = TT.template("in", "regular", "within", 7)
    assert a is TT.template("in", "regular", "within", 9)  # one template for n >= 2
    assert a is not TT.template("in", "regular", "within", 1)
