"""A Doorstop document reached twice, through a symbolic link to its folder inside the tree
(``tree/r_link -> r``), is one document: its items are listed once, with their own item
files, not twice."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from fretc.fretish.files import load_requirements

DOORSTOP = Path(__file__).resolve().parents[1] / "fixtures" / "requirements_tools" / "doorstop"


@pytest.mark.parametrize("link", ["r_link", "aaa", "zzz"])  # (before and after r in order)
def test_a_document_linked_into_its_tree_lists_its_items_once(tmp_path, link):
    tree = tmp_path / "tree"
    shutil.copytree(DOORSTOP, tree)
    want = [(e.id, e.origin.file) for e in load_requirements(tree)]
    os.symlink("r", tree / link)
    got = [(e.id, e.origin.file) for e in load_requirements(tree)]
    assert got == want
    assert all(f"{os.sep}{link}{os.sep}" not in f for _i, f in got)
