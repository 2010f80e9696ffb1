"""The fretc command line: --emit ltl/monitor/psl, JSON output, errors and exit codes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
R1 = str(ROOT / "requirements" / "r1.fret")


def run(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_emit_ltl_r1():
    res = run(R1, "--emit", "ltl")
    assert res.exit_code == 0
    assert "key     null,holding,eventually,satisfaction" in res.output
    assert "ft_inf  (G (too_close -> (F stopped)))" in res.output
    assert "pt      ((H (! too_close)) | (! ((! stopped) S ((! stopped) & too_close))))" \
        in res.output


def test_json_and_errors_do_not_stop_the_others(tmp_path):
    f = tmp_path / "reqs.fret"
    f.write_text("A: the sw shall always satisfy p and q\n"
                 "B: upon p the sw shall within 3 ticks satisfy q\n"
                 "C: globally the sw shall always satisfy p\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "ltl", "--json"])
    assert res.exit_code == 1
    data = json.loads(res.stdout)
    assert [d["id"] for d in data] == ["A", "B", "C"]
    assert data[0]["error"]["line"] == 1 and data[0]["error"]["column"] == 34
    assert "'&'" in data[0]["error"]["text"]  # the hint
    assert "globally" in data[2]["error"]["text"]
    b = data[1]
    assert set(b) >= {"id", "text", "key", "ft", "ft_inf", "pt", "variables"}
    assert b["key"] == "null,regular,within,satisfaction" and b["variables"] == ["p", "q"]


def test_emit_monitor_writes_an_importable_module(tmp_path):
    out = tmp_path / "r1_monitors.py"
    res = run(R1, "--emit", "monitor", "-o", str(out))
    assert res.exit_code == 0
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import r1_monitors as m; "
            "M = m.MONITORS['R1'](); "
            "print([M.step({'too_close': a, 'stopped': b}) for a, b in [(0, 0), (1, 0), (1, 1)]])")
    got = subprocess.run([sys.executable, "-I", "-S", "-c", code, str(tmp_path)],
                         capture_output=True, text=True, check=True).stdout.strip()
    assert got == "[True, False, True]"
    again = tmp_path / "again.py"
    run(R1, "--emit", "monitor", "-o", str(again))
    assert again.read_bytes() == out.read_bytes()


def test_emit_psl():
    res = run(R1, "--emit", "psl")
    assert "R1: [] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))" in res.output


def test_missing_file_is_a_usage_error():
    res = CliRunner().invoke(main, ["no/such.fret", "--emit", "ltl"])
    assert res.exit_code == 2


def test_console_script_runs_as_users_wrote_it():
    got = subprocess.run([sys.executable, "-m", "fretc", "requirements/r1.fret", "--emit", "ltl"],
                         cwd=ROOT, capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    assert "R1" in got.stdout


def test_files_with_the_same_name_get_distinct_modules(tmp_path):
    for folder, var in (("a", "p"), ("b", "q")):
        (tmp_path / folder).mkdir()
        # (ids unique across the files of a run)
        (tmp_path / folder / "reqs.fret").write_text(
            f"R{var}: the sw shall always satisfy {var}\n")
    out = tmp_path / "mods"
    res = run(str(tmp_path / "a" / "reqs.fret"), str(tmp_path / "b" / "reqs.fret"),
              "--emit", "monitor", "-o", str(out))
    assert res.exit_code == 0
    assert sorted(p.name for p in out.iterdir()) == ["reqs_2_monitors.py", "reqs_monitors.py"]
    assert "'q'" in (out / "reqs_2_monitors.py").read_text()


def test_user_text_reaches_the_terminal_escaped(tmp_path):
    """An id with U+202E, NUL, NEL and CR (a FRET export allows any id) is printed escaped in
    ``--emit monitor``'s ``skipped`` line and in ``fretc check``'s report."""
    f = tmp_path / "x.json"
    f.write_text(json.dumps([{"reqid": "R\u202eX\x00\x85\r", "project": "p",
                              "fulltext": "whenever p the sw shall immediately satisfy "
                                          "persists(2, q)"}]))
    raw = ("\u202e", "\x00", "\x85", "\r")
    res = CliRunner().invoke(main, [str(f), "--emit", "monitor", "-o",
                                    str(tmp_path / "m.py")])
    assert "skipped R\\u202eX\\x00\\x85\\x0d" in res.output
    res2 = CliRunner().invoke(main, ["check", str(f)])
    assert "R\\u202eX" in res2.output
    for out in (res.output, res2.output):
        assert not any(ch in out for ch in raw), out


def test_an_internal_error_is_one_line_and_exit_4(monkeypatch):
    """A defect escaping a command (here a RecursionError) is not a traceback with exit 1,
    the code of "violated": one line asking for a report, exit 4."""
    import fretc.cli.compile as compile_cmd

    def boom(*_a, **_k):
        raise RecursionError("maximum recursion depth exceeded")

    monkeypatch.setattr(compile_cmd, "_load", boom)
    res = CliRunner().invoke(main, [R1, "--emit", "psl"])
    assert res.exit_code == 4
    assert res.output.startswith("internal error: RecursionError")
    assert len(res.output.strip().splitlines()) == 1 and "Traceback" not in res.output


def test_a_reader_that_leaves_early_is_no_internal_error(tmp_path):
    """``fretc inspect LOG | head``: the pipe closes under fretc; it ends quietly (141, as a
    shell reports SIGPIPE, or 0 when everything was written first), never an internal
    error."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]
    p = subprocess.Popen([sys.executable, "-m", "fretc", "inspect",
                          str(root / "traces" / "nominal.mcap")], cwd=root,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.readline()
    p.stdout.close()
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) in (0, 141)
    assert "internal error" not in err and "Traceback" not in err
