"""A release's manifest (python -m fretc.qualification.manifest FILE) and ``fretc qualify
--manifest FILE``: the installed files compared with the release's, a file that differs
named and failing the run (exit 1), an unreadable manifest refused before anything is
written (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fretc.qualification.manifest import compare, main, manifest

from test_qualify import qualify


def test_the_installed_files_are_their_own_manifest_and_a_change_is_named():
    m = manifest()
    assert len(m["files"]) > 300 and all(len(h) == 64 for h in m["files"].values())
    assert compare(m) == {"version": m["version"], "changed": [], "missing": [], "extra": []}
    first = sorted(m["files"])[0]
    forged = {"version": "9.9.9", "files": {**m["files"], first: "0" * 64, "gone.py": "1" * 64}}
    del forged["files"][sorted(m["files"])[1]]
    got = compare(forged)
    assert got["changed"] == [first] and got["missing"] == ["gone.py"]
    assert got["extra"] == [sorted(m["files"])[1]] and got["version"] == "9.9.9"
    with pytest.raises(ValueError, match="not a fretc manifest"):
        compare({"files": [1, 2]})


def test_the_command_writes_a_manifest(tmp_path: Path, capsys):
    assert main([str(tmp_path / "m.json")]) == 0
    doc = json.loads((tmp_path / "m.json").read_text(encoding="utf-8"))
    assert doc == manifest()
    assert main([]) == 2


@pytest.mark.tor("TOR-QUA-001")
def test_qualify_fails_an_installation_that_is_not_the_release(tmp_path: Path):
    home = tmp_path / "home"
    home.mkdir()
    m = manifest()
    name = sorted(m["files"])[0]
    m["files"][name] = "0" * 64
    (tmp_path / "m.json").write_text(json.dumps(m), encoding="utf-8")
    got = qualify(["-o", str(tmp_path / "kit"), "--no-mutation", "--manifest",
                   str(tmp_path / "m.json")], home)
    assert got.returncode == 1, got.stdout + got.stderr
    assert "NOT THE RELEASE" in got.stderr and name in got.stderr
    doc = json.loads((tmp_path / "kit" / "report.json").read_text(encoding="utf-8"))
    assert doc["result"] == "failed" and doc["manifest"]["changed"] == [name]
    (tmp_path / "bad.json").write_text("[]", encoding="utf-8")
    got = qualify(["-o", str(tmp_path / "kit2"), "--manifest", str(tmp_path / "bad.json")],
                  home)
    assert got.returncode == 2 and not (tmp_path / "kit2").exists(), got.stderr
