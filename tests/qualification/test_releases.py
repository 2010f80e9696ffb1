"""Each release in releases/ is named everywhere a release is: its manifest reads as one
(:func:`fretc.qualification.manifest.compare` accepts it), and its version has a CHANGELOG
section and a section of the accomplishment summary."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fretc.qualification.manifest import compare

REPO = Path(__file__).resolve().parents[2]
MANIFESTS = sorted((REPO / "releases").glob("*/manifest.json"))


def test_there_is_a_release():
    assert MANIFESTS, "no releases/VERSION/manifest.json"


@pytest.mark.parametrize("path", MANIFESTS, ids=[p.parent.name for p in MANIFESTS])
def test_a_release_is_named_by_its_manifest_changelog_and_summary(path):
    doc = json.loads(path.read_text(encoding="utf-8"))
    version = path.parent.name
    assert doc["version"] == version and len(doc["files"]) > 100
    assert compare(doc)["version"] == version
    assert f"## [{version}] - " in (REPO / "CHANGELOG.md").read_text(encoding="utf-8")
    summary = REPO / "docs" / "qualification" / "accomplishment-summary.md"
    assert f"\n## {version} (" in summary.read_text(encoding="utf-8")
