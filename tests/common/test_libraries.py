"""fretc's parsers refuse a Lark that is not 1.x (ROS 2's lark-parser 0.12 in its place)
with the command that repairs it."""

from __future__ import annotations

import pytest

from fretc.common.libraries import LARK_REPAIR, LibraryError, check_lark


@pytest.mark.parametrize("version", ["0.12.0", "0.7.8", "x"])
def test_an_old_lark_is_refused_with_the_repair(version):
    with pytest.raises(LibraryError) as exc:
        check_lark(version)
    assert LARK_REPAIR in str(exc.value) and version in str(exc.value)


@pytest.mark.parametrize("version", ["1.1.9", "1.3.1", "2.0.0"])
def test_lark_1_and_later_pass(version):
    check_lark(version)


def test_the_parsers_check_the_lark_they_import(monkeypatch):
    import lark

    from fretc.fretish import parser

    monkeypatch.setattr(lark, "__version__", "0.12.0")
    with pytest.raises(LibraryError):
        parser.build_lark()
