"""``fretc shield``: the Safety System synthesized from the requirements (:mod:`fretc.shield`).

::

    fretc shield FILE... [--inputs A,B] [--outputs C,D] [-b BINDINGS] [--prefer LITERALS]
                 [--assume FILE]... [--fallback OUTPUTS] [--emit python|c|ros2|gwendolen]...
                 [-o DIR] [--prove] [--explain]
                 [--budget UNITS] [--memory-budget NODES]

Inputs and outputs default to the files' ``@inputs``/``@outputs`` (as ``fretc check``). Exit
status: 0 the shield was synthesized (and written, and proved with ``--prove``); 1 a game or
the proof ran past its budget (unknown), or the proof found a run violating an enforced
requirement; 2 input errors and refusals (a requirement that cannot be enforced, an
unrealizable set: the message says why).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from fretc.cli.options import (TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION, budget_options,
                               io_options, names_of,
                               exit_on_compile_errors, requirement_set, selection_options,
                               set_bindings_option, shown)

__all__ = ["shield_cmd", "FORMS"]

#: the forms ``--emit`` writes: name -> the writer module of :mod:`fretc.shield`
FORMS = ("python", "c", "ros2", "gwendolen")


@click.command("shield")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@io_options("The environment's variables; default: @inputs of the files.",
            "The controller's variables, which the shield corrects; default: @outputs of "
            "the files.")
@set_bindings_option("A binding file: outputs bound to one topic are corrected together, "
                     "never to values no single message gives; the ros2 form reads and "
                     "writes the bound topics.")
@selection_options
@click.option("--prefer", default=None, metavar="LITERALS",
              help="Among corrections changing equally few output atoms, prefer these "
              "values, first first: e.g. 'stopped,!stop_requested'.")
@click.option("--assume", "assume", multiple=True, type=click.Path(exists=True),
              metavar="FILE", help="Requirements of the environment (what it can do), taken "
              "as the games' assumptions: the environment loses a play in which it breaks "
              "one, a requirement over inputs they relate to outputs is enforced, --prove "
              "proves under them; the forms report when one breaks (repeatable).")
@click.option("--fallback", default=None, metavar="OUTPUTS",
              help="The outputs of a tick whose inputs cannot be read (a NaN, a missing "
              "value), which must keep every requirement from every state whatever the "
              "inputs: e.g. 'stopped,!moving,speed=0'; default: [shield] fallback of -b, "
              "else the shield's own.")
@click.option("--emit", "forms", multiple=True, type=click.Choice(FORMS),
              help="Write the shield in this form into DIR (repeatable).")
@click.option("-o", "--output", "out_dir", type=click.Path(file_okay=False), default=None,
              help="The folder the forms are written to.")
@click.option("--prove", is_flag=True, help="Prove with Spot that the shield, with any "
              "environment and any controller, satisfies every enforced requirement's "
              "ft_inf.")
@click.option("--explain", is_flag=True, help="Say, per enforced requirement, what the "
              "controller may still do under the shield.")
@click.option("--name", default=None, help="The shield's name (default: the first file's "
              "stem).")
@click.option("--margin", type=click.IntRange(min=0), default=0, show_default=True,
              metavar="TICKS", help="Meet every 'within' deadline TICKS ticks early: on a "
              "bus, a recorder or monitor ticking at another phase sees the shield's answers "
              "up to a tick late (the ROS 2 node: --margin 1).")
@budget_options("game")
@TICK_PERIOD_OPTION
@TEXT_ATTRIBUTE_OPTION
def shield_cmd(files: tuple[str, ...], inputs: str | None, outputs: str | None,
               bindings_file: str | None, component: str | None, only: str | None,
               exclude: str | None, prefer: str | None, assume: tuple[str, ...],
               fallback: str | None, forms: tuple[str, ...],
               out_dir: str | None, prove: bool, explain: bool, name: str | None,
               margin: int, budget: int, memory_budget: int, query_cpu: float,
               tick_period: str | None) -> None:
    """Synthesize the shield of requirement FILES: each tick it passes the controller's
    proposed outputs unchanged when they keep every requirement winnable, and otherwise
    changes the fewest outputs needed (the Safety System of Safe-ROS, generated)."""
    from fretc.check.budget import Budget
    from fretc.fretish.fret_variables import fret_declarations
    from fretc.shield.build import ShieldUnknown, build_shield, parse_preferences, with_margin
    from fretc.shield.fallback import declared_fallback, parse_fallback
    from fretc.shield.twists import twists_of, twists_where

    if forms and out_dir is None:
        raise click.UsageError("--emit needs -o DIR")
    rs, compiled, assumed = _read(files, assume, bindings_file, (component, only, exclude),
                                  tick_period)
    parts = rs.by_component() if component is None and inputs is None and outputs is None \
        else []
    if parts:  # (FRET: a component's requirements with its interface; a shield is one's)
        click.echo(shown("error: the requirements are of several FRET components ("
                         + ", ".join(name for name, _p in parts) + "), each with its own "
                         "Inputs and Outputs: give --component NAME (a shield is one "
                         "component's), or --inputs and --outputs"), err=True)
        sys.exit(2)
    as_written = rs.as_written
    ins = names_of(inputs)
    outs = names_of(outputs)
    if ins is None:
        ins = rs.inputs or []
    if outs is None:
        outs = rs.outputs or []
    if not outs:
        click.echo(shown("error: no outputs: give --outputs or @outputs in the files (the "
                         "variables the shield corrects)"), err=True)
        sys.exit(2)
    bindings = rs.bindings
    declared = parse_fallback(fallback)
    if declared is None:
        declared = declared_fallback(bindings_file)
    twists = twists_of(bindings_file)

    def make(ticks: int) -> Any:  # (the shield with every deadline ``ticks`` early)
        return build_shield(with_margin(compiled, ticks), ins, outs, bindings=bindings,
                            prefer=parse_preferences(prefer),
                            budget=Budget(work=budget, memory=memory_budget, cpu=query_cpu),
                            name=name or Path(files[0]).stem, fallback=declared,
                            assumptions=assumed, twists=twists,
                            twists_where=twists_where(bindings_file))

    try:
        shield = make(margin)
        node = _node_shield(make, shield, margin, bindings_file) if "ros2" in forms else None
    except ShieldUnknown as exc:
        click.echo(shown(f"unknown: {exc}"), err=True)
        sys.exit(1)
    click.echo(shown(_summary(shield)))
    for n in fret_declarations(as_written, shield.integers, bits=True)[1]:  # (the notes of the integers)
        click.echo(shown(f"  note: {n}"))
    code = 0
    if explain:
        from fretc.shield.explain import explain_text

        click.echo(shown(explain_text(shield, [*compiled, *assumed])))
    if prove:
        from fretc.shield.prove import prove_shield

        proof = prove_shield(shield, [*compiled, *assumed])
        click.echo(shown(proof.text()))
        code = 0 if proof.holds else 1
        code = max(code, _timing(shield, node, [*compiled, *assumed], bindings_file))
    if forms:
        assert out_dir is not None  # refused above without -o
        _write(shield, forms, out_dir, bindings, bindings_file, compiled, node,
               (files, assume))
    sys.exit(code)


def _read(files: Sequence[str], assume: Sequence[str], bindings_file: str | None,
          selection: tuple[str | None, str | None, str | None] = (None, None, None),
          tick_period: str | None = None) -> tuple[Any, list[Any], list[Any]]:
    """The requirement set (``selection``: ``--component``, ``--only``, ``--exclude``;
    ``tick_period``: ``--tick-period``), its requirements and the assumptions (``--assume``)
    compiled;
    exits 2 naming what cannot be compiled, an id both a requirement's and an assumption's,
    or no requirement."""
    from fretc.compiler.build import compile_entries

    component, only, exclude = selection
    rs = requirement_set(files, bindings_file, component=component, only=only, exclude=exclude,
                         tick_period=tick_period, bits=True)
    compiled = compile_entries(rs.entries)
    assumed = (compile_entries(requirement_set(assume, bindings_file, tick_period=tick_period,
                                               bits=True).entries)
               if assume else [])
    taken = {c.id for c in compiled}
    twice = sorted({c.id for c in assumed if c.id in taken})
    if twice:
        click.echo(shown(f"error: {', '.join(twice)}: both a requirement and an assumption "
                         "(--assume): give each one id"), err=True)
        sys.exit(2)
    exit_on_compile_errors(files, compiled, assumed)
    return rs, compiled, assumed


def _write(shield: Any, forms: Sequence[str], out_dir: str, bindings: Any,
           bindings_file: str | None, compiled: Sequence[Any],
           node: tuple[Any, int] | None,
           read: tuple[Sequence[str], Sequence[str]] = ((), ())) -> None:
    """Write the forms into ``out_dir`` and name each file written. ``read``: the
    requirement paths and ``--assume``'s: no file written is one of them, nor the binding
    file, and ``out_dir`` is not a folder of them (refused before any file is written).

    Raises:
        click.UsageError: a folder that cannot be written.
        OutputError: a file written would be an input
            (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    from fretc.common.errors import FretcError
    from fretc.shield.emit import render_forms, write_forms

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    req_files, req_folders = requirement_inputs(read[0])
    assumed, assumed_folders = requirement_inputs(read[1], "the assumption file (--assume)")
    names = render_forms(shield, forms, bindings=bindings, bindings_file=bindings_file,
                         compiled=compiled, node=node)  # (only their names: write_forms writes)
    refuse_outputs_over_inputs([("-o", Path(out_dir) / n) for n in names],
                               req_files + assumed + [("the binding file", bindings_file)],
                               [("-o", out_dir)], req_folders + assumed_folders)
    try:
        written = write_forms(shield, forms, Path(out_dir), bindings=bindings,
                              bindings_file=bindings_file, compiled=compiled, node=node)
    except OSError as exc:  # (-o names a file, a folder that cannot be written, a link
        # where a folder goes: fretc.common.outputs.OutputError)
        raise click.UsageError(f"cannot write the forms into -o {out_dir}: "
                               f"{exc.strerror or exc}") from None
    except FretcError:
        raise
    for path in written:
        click.echo(shown(f"wrote {path}"))


def _node_shield(make: Any, shield: Any, margin: int, bindings_file: str | None
                 ) -> tuple[Any, int] | None:
    """The ROS 2 node's shield and the ticks early it meets each deadline
    (:func:`fretc.shield.emit_ros2.node_margin`, at least ``--margin``); None without a
    period (the form refuses it then)."""
    from fretc.shield.emit_ros2 import latency_budget, node_margin

    if shield.period is None:
        return None
    ticks = max(margin, node_margin(shield.period, latency_budget(bindings_file)))
    return (shield if ticks == margin else make(ticks)), ticks


def _timing(shield: Any, node: tuple[Any, int] | None, compiled: Sequence[Any],
            bindings_file: str | None) -> int:
    """Print the timing ``--prove`` relies on, and prove the ROS 2 node's shield (its
    deadlines early) when the form is written; 1 when that proof fails, else 0."""
    from fretc.shield.emit_ros2 import latency_budget, node_margin
    from fretc.shield.prove import prove_shield

    if shield.period is None:
        click.echo("timing it relies on: the host steps one tick per tick of the requirements "
                   "(they declare no period)")
        return 0
    ms = f"{float(shield.period * 1000):g} ms"
    budget = latency_budget(bindings_file)
    ticks = node[1] if node is not None else node_margin(shield.period, budget)
    click.echo(f"timing it relies on: a tick every {ms}, its inputs read when it starts and "
               f"its outputs decided in it; on a bus (--emit ros2) each 'within' deadline is "
               f"met {ticks} tick(s) early: a reader at another phase sees the answers up to "
               f"a tick late, and the node's latency is within its "
               f"{float(budget * 1000):g} ms budget (measured, /diagnostics)")
    if node is None or node[0] is shield:
        return 0
    proof = prove_shield(node[0], compiled)
    click.echo(f"the ROS 2 node's shield (deadlines {ticks} tick(s) early): "
               + ("every enforced requirement holds" if proof.holds else "NOT PROVED"))
    return 0 if proof.holds else 1


def _summary(shield) -> str:
    """The terminal summary: per component its requirements and size; what is monitored
    only; the notes."""
    lines = [f"shield {shield.name}: inputs {', '.join(shield.inputs) or '-'}; outputs "
             f"{', '.join(shield.outputs)}"]
    for m in shield.machines:
        st = m.stats
        lines.append(f"  enforces {', '.join(m.requirements)}: {st.get('state_bits', 0)} state "
                     f"bits, winning region a BDD of {st.get('winning_region_bdd_nodes', 0)} "
                     f"nodes, {len(m.nodes)} table nodes")
    for g in shield.messages:
        lines.append(f"  corrected together (one message): {', '.join(g)}")
    for m in shield.machines:
        for v in dict.fromkeys(b["variable"] for b in m.bounds):
            mine = [b for b in m.bounds if b["variable"] == v]
            lines.append(f"  bounded by the inputs: {v} ({len(mine)} comparison"
                         f"{'s' * (len(mine) > 1)} with the inputs; which truth values numbers "
                         "give them is the environment's move): the number nearest the "
                         "proposal that gives the decided ones")
    for t in shield.twists:
        lines.append(f"  one twist: {', '.join(t)}: a correction scales them together (the "
                     "path's curvature kept) where the decided comparisons allow it")
    for rid, why in shield.monitored.items():
        lines.append(f"  monitored only: {rid}: {why}")
    if shield.assumptions:
        lines.append("  under the assumptions of the environment "
                     + ", ".join(a.id for a in shield.assumptions) + " ("
                     + ", ".join(dict.fromkeys(a.source.rsplit(":", 1)[0]
                                               for a in shield.assumptions))
                     + "): the environment loses a play in which it breaks one")
    if shield.fallback is not None and shield.fallback["outputs"]:
        lines.append("  fallback (a tick whose inputs cannot be read): " + ", ".join(
            (v if x else f"!{v}") if isinstance(x, bool) else f"{v}={x:g}"
            for v, x in shield.fallback["outputs"].items()))
    for n in shield.notes:
        lines.append(f"  note: {n}")
    return "\n".join(lines)

