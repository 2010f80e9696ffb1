"""The entries of a ``.fret`` file kept between runs (:mod:`fretc.fretish.entry_cache`): the
same entries as a parse, on every ``.fret`` file of the repository; never stale (another
text, name or parser code is a miss); a damaged entry is a miss; a file with a sentence
that does not parse is never kept."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from fretc.fretish import entry_cache, parser
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]


def _fret_files() -> list[Path]:
    """The repository's own ``.fret`` files (git's list), never a run's output in the clone
    (``.ci/kit/`` holds qualify's work folder, seeded syntax errors included)."""
    out = subprocess.run(["git", "ls-files", "*.fret"], cwd=ROOT, capture_output=True,
                         text=True)
    if out.returncode != 0:  # not a git checkout (an unpacked archive)
        return sorted(p for p in ROOT.rglob("*.fret")
                      if not any(part.startswith(".") for part in p.relative_to(ROOT).parts))
    return sorted(ROOT / f for f in out.stdout.split() if (ROOT / f).exists())


FILES = _fret_files()
TWO = ("R1: upon p the sw shall within 3 ticks satisfy q\n"
       "  rationale: a reason\n"
       "R2: in m the sw shall always satisfy x + 1 > 2.5\n")


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _no_parse(monkeypatch):
    """Make any parse fail, so that only kept entries can be read."""
    def refuse(*_a, **_k):
        raise AssertionError("parsed: the kept entries were not used")
    monkeypatch.setattr(parser, "_run", refuse)


def _entries(cache_dir) -> list[Path]:
    folder = cache_dir / entry_cache.KIND
    return sorted(folder.iterdir()) if folder.exists() else []


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_kept_entries_equal_a_parse(path, cache_dir, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    parsed = load_requirements(path)
    monkeypatch.setenv("FRETC_CACHE_DIR", str(cache_dir))
    assert load_requirements(path) == parsed  # (written)
    assert len(_entries(cache_dir)) == 1
    with monkeypatch.context() as m:
        _no_parse(m)
        assert load_requirements(path) == parsed  # (read back)


def test_another_text_name_or_code_is_a_miss(tmp_path, cache_dir, monkeypatch):
    fret = tmp_path / "r.fret"
    fret.write_text(TWO, encoding="utf-8")
    first = load_requirements(fret)
    (entry,) = _entries(cache_dir)
    fret.write_text(TWO.replace("3 ticks", "4 ticks"), encoding="utf-8")
    changed = load_requirements(fret)  # parsed again: the kept entry is another text's
    assert "4 ticks" in changed[0].text and changed[0].requirement != first[0].requirement
    assert _entries(cache_dir) == [entry]  # (replaced: one entry a file name)
    other = tmp_path / "s.fret"
    other.write_text(TWO.replace("3 ticks", "4 ticks"), encoding="utf-8")
    assert [e.source for e in load_requirements(other)] == [str(other)] * 2
    monkeypatch.setattr(entry_cache, "_CODE_KEY", "another parser")
    with monkeypatch.context() as m:
        _no_parse(m)
        with pytest.raises(AssertionError, match="parsed"):
            load_requirements(fret)


def test_a_damaged_entry_is_parsed_again(tmp_path, cache_dir):
    fret = tmp_path / "r.fret"
    fret.write_text(TWO, encoding="utf-8")
    first = load_requirements(fret)
    (entry,) = _entries(cache_dir)
    data = bytearray(entry.read_bytes())
    for damage in (bytes(data[:-5]), bytes(data[:-1]) + bytes([data[-1] ^ 1]), b"garbage"):
        entry.write_bytes(damage)
        assert load_requirements(fret) == first
        assert entry.read_bytes() == bytes(data)  # (written again)


def test_a_file_with_a_bad_sentence_is_never_kept(tmp_path, cache_dir):
    fret = tmp_path / "r.fret"
    fret.write_text(TWO + "R3: the sw shall always satisfy p &\n", encoding="utf-8")
    runs = [load_requirements(fret) for _ in range(2)]
    assert _entries(cache_dir) == []
    assert [str(e.error) for e in runs[0]] == [str(e.error) for e in runs[1]]
    assert runs[0][2].error is not None and "r.fret:4:" in str(runs[0][2].error)


def test_no_cache_folder_reads_as_before(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    fret = tmp_path / "r.fret"
    fret.write_text(TWO, encoding="utf-8")
    assert [e.id for e in load_requirements(fret)] == ["R1", "R2"]
