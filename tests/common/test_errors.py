"""One exception root (common/errors.py): every stage's input error is a
FretcError, and the fretc command reports one that no sub-command caught with exit code 2."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from fretc.compiler.ajpf import AjpfError
from fretc.check.realizability import RealizabilityError
from fretc.compiler.codegen import CodegenError, InvalidMonitorError
from fretc.compiler.semantics import SemanticsError
from fretc.cli import main
from fretc.common.errors import (CheckError, FretcError, FretishError, FretishFileError,
    FretishSyntaxError, InputError, Where, error_text)
from fretc.fretish.files import load_requirements
from fretc.fretish.limits import LimitError
from fretc.audit import AuditInputError
from fretc.audit.fleet.ray import RayUnavailable
from fretc.common.problems import BindingError, CsvError, FretcInputError, LogError, SignalError
from fretc.reports.write import ReportError
from fretc.logs.schema import FieldPathError


@pytest.mark.parametrize("cls, stage", [
    (FretishSyntaxError, FretishError), (FretishFileError, FretishError),
    (LimitError, FretishError), (SemanticsError, FretishError), (CodegenError, FretishError),
    (AjpfError, FretishError), (RealizabilityError, CheckError), (LogError, InputError),
    (CsvError, LogError), (BindingError, InputError), (SignalError, InputError),
    (FieldPathError, InputError), (AuditInputError, InputError),
    (RayUnavailable, AuditInputError), (ReportError, FretcError)])
def test_every_stage_derives_from_the_root(cls, stage):
    assert issubclass(cls, stage) and issubclass(cls, FretcError)


def test_former_bases_still_catch():
    assert FretcInputError is InputError
    assert issubclass(RealizabilityError, ValueError) and issubclass(FieldPathError, ValueError)
    assert not issubclass(InvalidMonitorError, FretcError)  # an internal error, exit code 4


def test_where_is_carried(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("R1: the sw shall always satisfy p\nR1: the sw shall always satisfy q\n",
                 encoding="utf-8")
    with pytest.raises(FretcError) as info:
        load_requirements([f])
    assert info.value.where.file == str(f) and info.value.where.line == 2
    e = BindingError("b.toml", "bad", line=3, col=7, variable="x")
    assert e.where == Where("b.toml", 3, 7) and str(e.where) == "b.toml:3:7"
    assert CsvError("t.csv", 4, "bad cell").where == Where("t.csv", 4)
    assert LogError("x.mcap", "not a log").where == Where("x.mcap")
    assert str(Where(topic="/scan", log_time_ns=5)) == "/scan @ 5 ns"
    assert error_text(ReportError("x")) == "error: x"
    assert error_text(e) == f"error: {e}"


def test_the_command_group_reports_an_uncaught_input_error(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("R1: the sw shall always satisfy p\n", encoding="utf-8")
    bad = tmp_path / "map.toml"
    bad.write_text("not = [toml\n", encoding="utf-8")
    res = CliRunner().invoke(main, [str(f), "--emit", "psl", "--psl-map", str(bad)])
    assert res.exit_code == 2 and res.exception is None or isinstance(res.exception, SystemExit)
    assert "cannot read the AJPF mapping" in res.output
