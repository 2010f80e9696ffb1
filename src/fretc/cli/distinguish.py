"""``fretc distinguish A B``: are two wordings of a requirement equivalent? Each of A and B is
a requirement text (``"upon p the sw shall within 5 ticks satisfy q"``, an ``ID:`` before it
allowed) or, with ``-r FILE``, the id of a requirement of FILE. The answer
(:mod:`fretc.check.distinguish`) comes first: ``not equivalent`` with the shortest trace on
which they disagree and each one's verdict on it, drawn as ``fretc explain`` draws traces;
``equivalent`` with the proof's source (Spot); or ``unknown`` and why.

Exit codes: 0 equivalent, 1 not equivalent, 2 an input error (a text that does not parse or
formalize, an id that is not in the file), 3 unknown.
"""

from __future__ import annotations

import dataclasses
import re
import sys

import click

from fretc.cli.options import TEXT_ATTRIBUTE_OPTION, text_attribute
from fretc.cli.options import shown as _shown

__all__ = ["distinguish_cmd"]

_ID_PREFIX = re.compile(r"\s*([A-Za-z0-9_.-]+)[ \t]*:\s+")


def _entry(arg: str, which: str, files: tuple[str, ...], period, by_id: dict):
    """(label, text, entry) of one argument: an id of ``files`` (no space in it) or a text."""
    from fretc.fretish.entry import RequirementEntry
    from fretc.fretish.parser import parse

    if not any(ch.isspace() for ch in arg.strip()):
        if arg not in by_id:
            where = ", ".join(files) if files else "no file (give -r FILE)"
            raise click.UsageError(f"{arg!r} is not a requirement text (it has no space) nor "
                                   f"an id of {where}")
        e = by_id[arg]
        return arg, e.text, dataclasses.replace(e, id=which)
    m = _ID_PREFIX.match(arg)
    label = m.group(1) if m else which
    text = arg[m.end():] if m else arg.strip()
    e = RequirementEntry(which, text, f"<{label}>", 1, 1, tick_period=period)
    e.requirement = parse(text, source=f"<{label}>")
    return label, text, e


@click.command("distinguish")
@click.argument("a")
@click.argument("b")
@click.option("-r", "--requirements", "files", multiple=True, type=click.Path(exists=True),
              help="Requirement file(s) in which A and B may be ids (repeatable).")
@click.option("--tick-period", default=None, metavar="DURATION",
              help="The tick period of the texts' durations in time units (e.g. '100 ms'); "
                   "default: the -r file's @tick_period.")
@click.option("--max-ticks", type=click.IntRange(1, 100_000), default=2048, show_default=True,
              help="The longest trace the breadth-first search builds.")
@click.option("--svg", "svg_path", type=click.Path(dir_okay=False), default=None,
              help="Also draw the distinguishing trace as an SVG in FILE (when there is one).")
@TEXT_ATTRIBUTE_OPTION
def distinguish_cmd(a: str, b: str, files: tuple[str, ...], tick_period: str | None,
                    max_ticks: int, svg_path: str | None) -> None:
    """Compare two wordings A and B (texts, or ids of -r FILE): "not equivalent" and the
    shortest trace on which their verdicts differ (exit 1), "equivalent" and the proof
    (exit 0), or "unknown" and why (exit 3)."""
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements, parse_tick_period
    from fretc.check.distinguish import distinguish
    from fretc.reports.distinction import distinction_text

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    refuse_outputs_over_inputs([("--svg", svg_path)], requirement_inputs(files)[0])
    entries = load_requirements(list(files), text_attribute=text_attribute()) if files else []
    by_id = {e.id: e for e in entries}
    period = None
    if tick_period is not None:
        try:
            period = parse_tick_period(tick_period)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint="--tick-period") from None
    elif entries:
        period = next((e.tick_period for e in entries if e.tick_period is not None), None)
    (la, ta, ea), (lb, tb, eb) = (_entry(x, w, files, period, by_id)
                                  for x, w in ((a, "A"), (b, "B")))
    if la == lb:  # the same id: a requirement and its edited wording
        la, lb = f"{la} (A)", f"{lb} (B)"
    ca, cb = compile_entries([ea, eb])
    for c, label in ((ca, la), (cb, lb)):
        if c.error is not None:
            raise c.error
        if c.formalization is None:
            click.echo(_shown(f"error: {label} is free-form: it has no formalization to "
                              "compare"), err=True)
            sys.exit(2)
    d = distinguish(ca, cb, max_ticks=max_ticks)
    click.echo(_shown(distinction_text(d, la, ta, lb, tb)), nl=False)
    if svg_path is not None and d.trace is not None:
        from fretc.common.outputs import write_file
        from fretc.reports.distinction import distinction_svg

        write_file(svg_path, distinction_svg(d, la, ta, lb, tb))
        click.echo(_shown(f"wrote {svg_path}"), err=True)
    sys.exit(0 if d.equivalent else 1 if d.equivalent is False else 3)
