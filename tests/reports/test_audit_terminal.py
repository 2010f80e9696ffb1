"""The terminal output of fretc audit: a compact default (the README's first
command prints its summary within the first screen), ``--verbose`` windows with unique
column headers and a marker where a window jumps, parse errors outside table cells with
their caret intact."""

from __future__ import annotations

import os
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
TRACES = ROOT / "traces"


def _run(*args):
    return CliRunner().invoke(main, ["audit", "--no-progress", *map(str, args)])


def test_main_job_summary_fits_one_screen():
    res = _run("--requirements", ROOT / "requirements", TRACES)
    assert res.exit_code == 1
    lines = res.output.splitlines()
    assert len(lines) <= 60, len(lines)  # was 241
    assert lines[-1].startswith("33 satisfied, 8 vacuous, 7 violated, 0 unknown, 0 error (exit 1")


def test_verbose_windows_have_unique_headers_and_gap_markers():
    res = _run("-r", ROOT / "requirements", TRACES / "interceptor_fault.mcap",
               TRACES / "sif_disabled.mcap", "--verbose")
    heads = [l.replace(" @", "@").split() for l in res.output.splitlines()
             if l.startswith("tick ")]
    r3 = next(h for h in heads if "forwarded_zero" in h)
    assert "…linear.x" in r3 and "…linear.y" in r3 and "…linear.z" in r3
    for h in heads:
        assert len(h) == len(set(h)), h
    assert any("…" in l and "ticks" in l for l in res.output.splitlines())  # R1's jump
    compact = _run("-r", ROOT / "requirements", TRACES / "interceptor_fault.mcap")
    assert not any(l.startswith("tick ") for l in compact.output.splitlines())


def test_parse_errors_are_printed_outside_the_table_with_the_caret(tmp_path):
    (tmp_path / "bad.fret").write_text(
        "B1: whenever too_close agilex_agent shall eventualy satisfy stopped\n")
    (tmp_path / "bad.bindings.toml").write_text(
        (ROOT / "requirements" / "safe_ros.bindings.toml").read_text())
    res = _run("-r", tmp_path / "bad.fret", TRACES / "sif_disabled.mcap")
    assert res.exit_code == 2
    lines = res.output.splitlines()
    carets = [i for i, l in enumerate(lines) if l.strip() == "^"]
    assert carets
    for i in carets:
        src = lines[i - 1]
        assert src[lines[i].index("^"):].startswith("eventualy"), (src, lines[i])


def _speed_log(tmp_path, value):
    from _logs import MS, twist, write_mcap
    msgs = [("/cmd", "geometry_msgs/msg/Twist", k * 100 * MS + 7 * MS,
             twist(value if k == 30 else 0.5)) for k in range(50)]
    log = write_mcap(tmp_path / "speed.mcap", msgs)
    (tmp_path / "s.fret").write_text("S1: the bot shall always satisfy speed <= 1.0\n")
    (tmp_path / "s.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nspeed = "/cmd.linear.x"\n')
    return log


def test_a_value_beside_its_threshold_shows_which_side_it_is_on(tmp_path):
    """Before, the terminal showed ``1`` for a speed of 1.000158 at the violation of
    ``speed <= 1.0``; every value shown reads back as the value sampled."""
    import json
    log = _speed_log(tmp_path, 1.000158)
    res = _run("-r", tmp_path / "s.fret", log, "--verbose", "--json", tmp_path / "a.json")
    assert res.exit_code == 1, res.output
    assert "1.000158" in res.output
    doc = json.loads((tmp_path / "a.json").read_text())
    rows = doc["logs"][0]["verdicts"][0]["values"]["speed"]
    assert any(r["value"] == 1.000158 for r in rows)
    from fretc.reports.verdicts import format_value
    for x in (1.000158, 0.1 + 0.2, 1e-9, 123456789.125, 2.0, -0.5):
        assert float(format_value(x)) == x
    assert format_value(2.0) == "2" and format_value(True) == "T"


def test_a_table_of_many_instances_lists_only_what_did_not_pass():
    """1,001 verdicts on one log (a per-entity requirement's instances): no matrix row per
    instance, but every verdict that is not a plain pass, and the count of all."""
    from rich.console import Console

    from fretc.audit.verdict import LogAudit, Verdict
    from fretc.reports.terminal import MATRIX_ROWS_MAX, print_summary

    def log(n: int) -> LogAudit:
        vs = [Verdict(log="run.mcap", requirement=f"T[track={k}]",
                      verdict="unknown" if k == 7 else "satisfied") for k in range(n)]
        return LogAudit(log="run.mcap", kind="mcap", verdicts=vs)

    for n, matrix in ((MATRIX_ROWS_MAX, True), (MATRIX_ROWS_MAX + 1, False)):
        console = Console(record=True, width=120)
        print_summary(console, [log(n)], details=False)
        text = console.export_text()
        assert ("T[track=999]" in text) is matrix, n
        assert "T[track=7]" in text and "unknown" in text
        assert ("only verdicts that are not complete passes are listed: 1 of "
                f"{n}" in text) is not matrix


def test_the_list_of_many_instances_keeps_every_name_whole_and_aligned():
    """The list printed instead of the matrix: one line per verdict that is not a plain
    pass, columns aligned by display width (a wide character counts two), a name longer
    than the console never cut, and each log named as the working directory sees it."""
    from rich.console import Console

    from fretc.audit.verdict import LogAudit, Verdict
    from fretc.reports.terminal import MATRIX_ROWS_MAX, print_summary

    long_key = "k" * 150
    names = ["T[track=\u969c]", f"T[track={long_key}]"]
    vs = [Verdict(log="run.mcap", requirement=f"T[track={k}]", verdict="satisfied")
          for k in range(MATRIX_ROWS_MAX)]
    vs += [Verdict(log="run.mcap", requirement=n, verdict="unknown") for n in names]
    console = Console(record=True, width=80)
    print_summary(console, [LogAudit(log=os.path.abspath("run.mcap"), kind="mcap",
                                     verdicts=vs)], details=False)
    lines = console.export_text().splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("log "))
    rows = lines[head + 1:head + 3]
    assert [r.split()[:2] for r in rows] == [["run.mcap", n] for n in names]
    from rich.cells import cell_len
    # the verdict column starts at the same display column on every line
    starts = [cell_len(line[:line.index(word)]) for line, word in
              zip(lines[head:head + 3], ("verdict", "unknown", "unknown"))]
    assert len(set(starts)) == 1, lines[head:head + 3]
    assert "only verdicts that are not complete passes are listed: 2 of 1002" in "\n".join(lines)


def test_violations_are_printed_as_rich_wraps_them_whether_their_lines_fit_or_not():
    """The violations' evidence printed without rich's word wrap when every line fits is the
    text rich's wrap gives; a line too long for the console is still wrapped by rich."""
    from rich.console import Console

    from fretc.audit.verdict import FirstViolation, LogAudit, TimePoint, Verdict
    from fretc.reports.terminal import _violation_text, print_summary

    for words in (3, 40):  # (a short requirement text, and one wider than the console)
        v = Verdict(log="run.mcap", requirement="R1", verdict="violated",
                    text=" ".join(["the robot shall always satisfy speed <= 1"] * words),
                    first_violation=FirstViolation(at=TimePoint(3, 300, 299), obligation="q",
                                                   reason="q is false at tick 3"))
        la = LogAudit(log="run.mcap", kind="mcap", verdicts=[v], start_time_ns=0)
        ours, rich_wrapped = Console(record=True, width=100), Console(record=True, width=100)
        print_summary(ours, [la])
        text = ours.export_text()
        rich_wrapped.print(_violation_text(la, v), highlight=False)
        want = rich_wrapped.export_text()
        assert want.strip() and want in text, (words, text)
        assert max(map(len, text.splitlines())) <= 100


def test_violation_headings_give_names_and_texts_as_written_in_one_text():
    """Each violation's heading names the requirement, log and text as written (rich markup
    and emoji codes in them are not applied), the name and "violated" in bold red; printed
    together, the violations are each one's own text, a blank line between them."""
    from rich.console import Console

    from fretc.audit.verdict import FirstViolation, LogAudit, TimePoint, Verdict
    from fretc.common.textsafe import terminal_text
    from fretc.reports.terminal import _violation_text, print_summary

    def violated(name, text):
        return Verdict(log="[red]r:fire:.mcap", requirement=name, verdict="violated", text=text,
                       first_violation=FirstViolation(at=TimePoint(3, 300, 299), obligation="q",
                                                      reason="q is false at tick 3"))

    vs = [violated("R[x=1]", "shall [bold]always[/bold] :fire: hold"),
          violated("S\nT", "b\n\u202eevil")]
    la = LogAudit(log="[red]r:fire:.mcap", kind="mcap", verdicts=vs, start_time_ns=0)
    heading = _violation_text(la, vs[0])
    assert heading.plain.startswith(
        "\nR[x=1] violated on [red]r:fire:.mcap: shall [bold]always[/bold] :fire: hold\n")
    assert [heading.plain[s.start:s.end] for s in heading.spans
            if str(s.style) == "bold red"] == ["R[x=1] violated"]
    name, text = (terminal_text(x, keep="") for x in ("S\nT", "b\n\u202eevil"))
    assert "\n" not in name + text and "\u202e" not in text
    assert _violation_text(la, vs[1]).plain.startswith(
        f"\n{name} violated on [red]r:fire:.mcap: {text}\n")
    ours, alone = Console(record=True, width=200), Console(record=True, width=200)
    print_summary(ours, [la])
    for v in vs:
        alone.print(_violation_text(la, v), highlight=False)
    assert alone.export_text(styles=True) in ours.export_text(styles=True)


def test_a_log_is_named_from_the_working_directory_of_the_moment(tmp_path, monkeypatch):
    """:func:`short_log_name` is kept per path, but follows a change of directory."""
    from fretc.reports.terminal import short_log_name

    log = tmp_path / "a" / "run.mcap"
    log.parent.mkdir()
    monkeypatch.chdir(tmp_path)
    assert short_log_name(str(log)) == os.path.join("a", "run.mcap")
    monkeypatch.chdir(log.parent)
    assert short_log_name(str(log)) == "run.mcap"
    monkeypatch.chdir(tmp_path.parent)
    assert short_log_name(str(log)) == os.path.join(tmp_path.name, "a", "run.mcap")
    assert short_log_name("ws://host:8765") == "ws://host:8765"


def test_a_note_of_changes_between_ticks_is_printed_only_for_a_verdict_that_has_them():
    """The log's notes name a variable's changes no tick sampled (its verdict's
    ``missed_changes``), and only those: a note that merely starts like one is not."""
    import io

    from rich.console import Console

    from fretc.audit.verdict import LogAudit, Verdict
    from fretc.reports.terminal import print_summary

    note = "stop: 2 messages of /stop that no tick sampled would have changed its value"
    seen = Verdict("l.mcap", "A", verdict="satisfied", notes=[note], missed_changes={"stop": 2})
    other = Verdict("l.mcap", "B", verdict="satisfied", notes=[note])
    out = io.StringIO()
    print_summary(Console(file=out, width=200), [LogAudit(log="l.mcap", verdicts=[seen, other])])
    lines = [line for line in out.getvalue().splitlines() if "between ticks" in line]
    assert len(lines) == 1 and "A: stop: 2 messages" in lines[0], lines


def test_names_are_printed_as_given_never_as_emoji(tmp_path):
    """A log named ``:fire:.mcap`` is printed by that name: rich's emoji codes are not
    applied to what the audit prints (it would name a log that does not exist)."""
    import shutil

    log = tmp_path / ":fire:.mcap"
    shutil.copy(TRACES / "stop_delay.mcap", log)
    res = _run("--requirements", ROOT / "requirements", log, "--no-progress")
    assert res.exit_code == 1, res.output
    assert f"{tmp_path}/:fire:.mcap" in res.output.replace("\n", "")
    assert "\N{FIRE}" not in res.output


def test_the_progress_bar_shows_log_names_as_given():
    """The progress bar's label of a log is its name, not rich markup or emoji codes."""
    from rich.console import Console

    from fretc.reports.progress import AuditProgress

    prog = AuditProgress(Console(file=open(os.devnull, "w"), emoji=False), 1)
    prog.start(0, "/runs/[bold]:fire:.mcap")
    (task,) = [t for t in prog.progress.tasks if t.id == prog.tasks[0]]
    assert prog.progress.columns[0].render(task).plain == "/runs/[bold]:fire:.mcap"
