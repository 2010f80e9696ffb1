"""Option definitions shared by the ``fretc`` commands, and the click glue around the audit.

``audit_input_options`` (what to audit and how) and ``ray_options`` (``--ray [ADDRESS]``,
``--retries N``) decorate ``fretc audit``, ``fretc report`` and ``fretc watch``;
``io_options``, ``set_bindings_option``, ``budget_options`` and :func:`requirement_set`
(the files read, each requirement's tick period) are those of ``fretc check``, ``fretc
shield`` and ``fretc testgen``;
:func:`audit_config` turns their values into a :class:`fretc.audit.AuditConfig` and
:func:`run_audits` runs the audit locally or on Ray (:mod:`fretc.audit.fleet.ray`) as the options
say. Only click is imported at module level, so the command starts fast; the engine loads
on first use.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, TYPE_CHECKING, TypeVar

import click

from fretc.common.textsafe import visible

if TYPE_CHECKING:
    from fretc.audit import AuditConfig
    from fretc.audit.fleet.workers import LogProgress
    from fretc.audit.model import AuditPlan

__all__ = ["TEXT_ATTRIBUTE_OPTION", "text_attribute", "BRIDGE_GAPS_OPTION", "bridge_gaps",
           "audit_input_options", "live_input_options", "audit_config", "ray_options",
           "run_audits", "META", "FleetError", "shown", "FiniteRange", "statistics_options",
           "names_of", "io_options", "set_bindings_option", "budget_options", "RequirementSet",
           "requirement_set", "with_safety", "selection_options", "exit_on_compile_errors",
           "requirement_inputs", "refuse_outputs_over_inputs", "refuse_folder_over_inputs"]


class FiniteRange(click.FloatRange):
    """click's ``FloatRange`` that also refuses NaN and the infinities, which click's range
    lets through (every comparison with NaN is false): a usage error, exit 2."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None
                ) -> Any:
        """The float of ``value`` in the range; fails (usage error) otherwise."""
        rv = super().convert(value, param, ctx)
        if not math.isfinite(rv):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return rv


def statistics_options(f: F) -> F:
    """``--confidence``, ``--trial`` and ``--unknown-runs`` of the statistics of probability
    requirements (``fretc audit``, ``fretc estimate``; :mod:`fretc.audit.fleet.statistics`)."""
    for opt in reversed((
        click.option("--confidence", type=FiniteRange(0.5, 1, max_open=True), default=0.95,
                     show_default=True,
                     help="Confidence of the intervals, in [0.5, 1) (a lower one shrinks the "
                          "interval to about the estimate, deciding bounds the trials do not "
                          "support)."),
        click.option("--trial", type=click.Choice(["trigger", "run"]), default="trigger",
                     show_default=True,
                     help="What one trial of a 'with probability' requirement is: each "
                          "trigger whose obligation the log decides (FRET's bound is per "
                          "trigger; the triggers of a run counted as a cluster), or each run "
                          "(the stronger per-run reading)."),
        click.option("--unknown-runs", type=click.Choice(["worst-case", "exclude", "fail"]),
                     default="worst-case", show_default=True,
                     help="Unknown and error runs, and triggers of unknown outcome: trials "
                          "that could have gone either way, the interval spanning every "
                          "outcome ('fail' is an old name of it), or left out (exclude). "
                          "Never as satisfied."))):
        f = opt(f)
    return f


#: a command function (the option decorators return it with their options added)
F = TypeVar("F", bound=Callable[..., Any])

#: Key of the Ray options in the click context's ``meta``.
META = "fretc.fleet"


def shown(text: str) -> str:
    """Text for the terminal: control and bidi characters escaped, lines kept
    (:func:`fretc.common.textsafe.visible`)."""
    return visible(text, keep="\n")


def live_input_options(f: F) -> F:
    """:func:`audit_input_options` without ``-j/--jobs`` (``fretc watch`` audits one run)."""
    return audit_input_options(f, jobs=False)


#: ``-r/--requirements FILE`` (repeatable): the requirements of an audit, and of the
#: simulator's campaigns (``fretc falsify``, ``fretc estimate``) that audit their runs
REQUIREMENTS_OPTION = click.option(
    "-r", "--requirements", "requirements", multiple=True, type=click.Path(exists=True),
    help="Requirement file (.fret, FRET JSON export, .reqif/.reqifz) or folder (of them, or "
         "a Doorstop tree); repeatable. Default: ./requirements.")
#: ``-b/--bindings FILE`` (repeatable): the signal bindings of those audits
BINDINGS_OPTION = click.option(
    "-b", "--bindings", "bindings", multiple=True, type=click.Path(exists=True),
    help="Signal binding file (TOML); repeatable. Default: *.bindings.toml beside the "
         "requirements.")
#: ``--space FILE``: the scenario space the simulator's campaigns sample or search
SPACE_OPTION = click.option(
    "--space", "space_path", required=True, type=click.Path(exists=True, dir_okay=False),
    help="The scenario space (TOML, sim/spaces/*.toml): the base scenario, the simulator's "
         "seed and each parameter's [low, high] range (uniform) or distribution (estimate "
         "samples it, falsify searches its range).")
#: ``--safety shield:DIR``: the simulator's runs with a generated shield (fretc.sim.shielded)
SAFETY_OPTION = click.option(
    "--safety", default=None, metavar="shield:DIR",
    help="Every run with the shield fretc shield --emit python -b BINDINGS wrote into DIR in "
         "place of the hand-written SIF and interceptor.")
def with_safety(space: Any, safety: str | None) -> Any:
    """``space`` (:class:`fretc.sim.space.Space`) with every run's Safety System ``safety``
    (``--safety shield:DIR``: a generated shield), checked now rather than in the first run
    (``fretc falsify``, ``fretc estimate``).

    Raises:
        click.BadParameter: a value that names no shield folder."""
    if safety is None:
        return space
    from dataclasses import replace

    from fretc.sim.run import shield_of

    try:
        shield_of(safety)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--safety") from None
    return replace(space, safety=safety)


#: ``--ray [ADDRESS]`` of the simulator's campaigns: the runs simulated and audited on Ray
SIMULATOR_RAY_OPTION = click.option(
    "--ray", "ray", is_flag=False, flag_value="local", default=None, metavar="[ADDRESS]",
    help="Simulate and audit the runs in parallel on Ray: a local Ray for the run, or "
         "ADDRESS of a cluster; the same answer as without. Needs pip install 'fretc[ray]'.")


def audit_input_options(f: F, jobs: bool = True) -> F:
    """The options that say what to audit and how (shared by ``fretc audit`` and
    ``fretc report``): requirements, bindings, tick, time base, jobs (unless ``jobs`` is
    False), window."""
    options = [
        REQUIREMENTS_OPTION,
        BINDINGS_OPTION,
        click.option("--bind", "inline", multiple=True, metavar="NAME=EXPR",
                     help="Bind a FRET variable inline, e.g. "
                          "--bind 'too_close=min(/scan.ranges) < 0.9'."),
        click.option("--tick-period", default=None, metavar="DURATION",
                     help="Fixed tick with sample-and-hold, e.g. \"100 ms\" (overrides the "
                          "bindings)."),
        click.option("--tick-topic", default=None, metavar="TOPIC",
                     help="One tick per message of TOPIC (overrides the bindings)."),
        click.option("--time-base", type=click.Choice(["log", "header", "header-where-stamped"]),
                     default=None,
                     help="Message time: log time (default), header.stamp, or header.stamp "
                          "where a message has a header and log time where it has none."),
        ALLOWANCE_OPTION,
        click.option("-j", "--jobs", type=click.IntRange(min=1), default=1,
                     show_default=True, help="Audit this many logs in parallel processes."),
        click.option("--window", type=click.IntRange(min=0), default=5, show_default=True,
                     help="Ticks of values kept each side of a trigger and a violation."),
        MSG_PATH_OPTION,
        TEXT_ATTRIBUTE_OPTION,
        BRIDGE_GAPS_OPTION,
        MAX_ENTITIES_OPTION,
    ]
    if not jobs:
        del options[-6]
    for option in reversed(options):
        f = option(f)
    return f


#: ``--msg-path DIR`` (repeatable): message types a log does not carry (logs.msg_path)
MSG_PATH_OPTION = click.option(
    "--msg-path", "msg_path", multiple=True, type=click.Path(exists=True, file_okay=False),
    help="Folder of the .msg/.idl files of message types a log does not store (laid out as "
         "PKG/msg/TYPE.msg, or a ROS 2 install/ or share/ tree); repeatable.")


#: Key of ``--text-attribute``'s value in the click context's ``meta``.
TEXT_META = "fretc.text_attribute"


def _store_text_attribute(ctx, param, value):
    if value is not None:
        ctx.meta[TEXT_META] = value
    return value


#: ``--text-attribute NAME``: the attribute of a ReqIF / Doorstop requirement holding its
#: FRETish text (:mod:`fretc.fretish.sources`); kept in the context (:func:`text_attribute`)
TEXT_ATTRIBUTE_OPTION = click.option(
    "--text-attribute", default=None, metavar="NAME", expose_value=False,
    callback=_store_text_attribute,
    help="ReqIF/Doorstop requirements: the attribute holding the FRETish text. Default: "
         "the attribute named FRETish, else the requirement text (ReqIF.Text, Doorstop "
         "text).")


#: Key of ``--bridge-gaps``' value (ns) in the click context's ``meta``.
BRIDGE_META = "fretc.bridge_gaps"


def _store_bridge_gaps(ctx, param, value):
    if value is None:
        return None
    from fretc.common.units import parse_duration

    try:
        ctx.meta[BRIDGE_META] = parse_duration(value)
    except ValueError as exc:
        raise click.BadParameter(str(exc), ctx=ctx, param=param) from None
    return value


#: ``--bridge-gaps DURATION``: hold values over gaps shorter than it (docs/guide/audits.md)
BRIDGE_GAPS_OPTION = click.option(
    "--bridge-gaps", default=None, metavar="DURATION", expose_value=False,
    callback=_store_bridge_gaps,
    help="Hold the value before a gap over it when the gap (a ULog dropout, a damaged chunk, "
         "a message not decoded) is shorter than DURATION, e.g. 50ms; every gap bridged is "
         "listed. Default: none (a gap's ticks are unknown).")


#: Key of ``--allowance``'s values (topic -> ns) in the click context's ``meta``.
ALLOWANCE_META = "fretc.allowance"


def _store_allowance(ctx: click.Context, param: click.Parameter, values: tuple[str, ...]
                     ) -> tuple[str, ...]:
    """``--allowance TOPIC=DURATION`` (repeatable) -> ``ctx.meta[ALLOWANCE_META]`` (topic ->
    ns, :func:`fretc.logs.allowance.parse_allowance`).

    Raises:
        click.BadParameter: no ``=``, a bad topic name, a negative or malformed duration,
            one topic given two allowances (exit 2, the option named)."""
    if not values:
        return values
    from fretc.logs.allowance import parse_allowance
    from fretc.signals.bindings.paths import topic_name

    got: dict[str, int] = {}
    for value in values:
        topic, eq, duration = value.partition("=")
        name = topic_name(topic.strip())
        try:
            if not eq or name is None:
                raise ValueError(f"{value!r} is not TOPIC=DURATION (e.g. "
                                 "/cmd_vel_filtered=120ms)")
            ns = parse_allowance(duration)
        except ValueError as exc:
            raise click.BadParameter(str(exc), ctx=ctx, param=param) from None
        if got.setdefault(name, ns) != ns:
            raise click.BadParameter(f"{name} is given two allowances", ctx=ctx, param=param)
    ctx.meta[ALLOWANCE_META] = got
    return values


#: ``--allowance TOPIC=DURATION`` (repeatable): a topic read earlier (fretc.logs.allowance)
ALLOWANCE_OPTION = click.option(
    "--allowance", "allowance", multiple=True, metavar="TOPIC=DURATION", expose_value=False,
    callback=_store_allowance,
    help="Read the messages of TOPIC as if logged DURATION earlier (a reaction allowance: "
         "a shield node's answers, seen on the bus up to its latency budget and a tick "
         "after the tick they answer, judged at that tick), e.g. "
         "--allowance /cmd_vel_filtered=120ms; repeatable. Over a binding file's [audit] "
         "allowance. Stated in the summary and the JSON. Default: none.")


def allowance() -> tuple[tuple[str, int], ...]:
    """The running command's ``--allowance`` as (topic, ns) pairs, topics sorted (``()``:
    not given)."""
    ctx = click.get_current_context(silent=True)
    got = ctx.meta.get(ALLOWANCE_META, {}) if ctx is not None else {}
    return tuple(sorted(got.items()))


#: Key of ``--max-entities``' value in the click context's ``meta``.
MAX_ENTITIES_META = "fretc.max_entities"

#: ``--max-entities N``: entities of one per-entity requirement judged per log
MAX_ENTITIES_OPTION = click.option(
    "--max-entities", type=click.IntRange(min=1), default=None, metavar="N",
    expose_value=False,
    callback=lambda ctx, _p, v: ctx.meta.__setitem__(MAX_ENTITIES_META, v) if v else None,
    help="Judge at most N entities of one per-entity requirement per log (docs/bindings.md, "
         "\"One verdict per entity\"); past it, an error verdict names the rest. It bounds "
         "the memory that grows with the entities (each judged keeps its key, times and "
         "verdict: about 150 bytes and 8 a tick of its life), with --json or without; what "
         "grows with the log's messages and ticks is bounded by the log. Default: 1,000,000.")


def bridge_gaps() -> int | None:
    """The running command's ``--bridge-gaps`` in ns (None: not given)."""
    ctx = click.get_current_context(silent=True)
    return ctx.meta.get(BRIDGE_META) if ctx is not None else None


def text_attribute() -> str | None:
    """The running command's ``--text-attribute`` (None: not given, or no command runs)."""
    ctx = click.get_current_context(silent=True)
    return ctx.meta.get(TEXT_META) if ctx is not None else None


def audit_config(requirements: tuple[str, ...], bindings: tuple[str, ...],
                 inline: tuple[str, ...], tick_period: str | None, tick_topic: str | None,
                 time_base: str | None, window: int, msg_path: tuple[str, ...] = ()
                 ) -> AuditConfig:
    """The :class:`fretc.audit.AuditConfig` of :func:`audit_input_options`' values
    (requirements default to ./requirements; raises ``click.UsageError`` without one)."""
    from fretc.audit import AuditConfig  # lazy: numpy and the engine only when run

    if not requirements:
        if not os.path.isdir("requirements"):
            raise click.UsageError("no --requirements given and no ./requirements folder")
        requirements = ("requirements",)
    return AuditConfig(requirements=tuple(requirements),
                       bindings=tuple(bindings) if bindings else None, inline=tuple(inline),
                       tick_period=tick_period, tick_topic=tick_topic, time_base=time_base,
                       window=window, msg_path=tuple(msg_path),
                       text_attribute=text_attribute(), bridge_gaps_ns=bridge_gaps(),
                       max_entities=_max_entities(), allowance=allowance())


def _max_entities() -> int | None:
    """The running command's ``--max-entities`` (None: not given)."""
    ctx = click.get_current_context(silent=True)
    return ctx.meta.get(MAX_ENTITIES_META) if ctx is not None else None


class FleetError(click.ClickException):
    """Ray cannot be started or reached: printed as ``Error: ...``, exit code 2."""

    exit_code = 2


def _store(ctx, param, value):
    if value is not None:
        ctx.meta.setdefault(META, {})[param.name] = value
    return value


def ray_options(f: F) -> F:
    """``--ray [ADDRESS]`` and ``--retries N`` (values kept in the click context; read by
    :func:`run_audits`), for ``fretc audit``, ``fretc report`` and ``fretc watch``."""
    f = click.option("--retries", type=click.IntRange(min=0), default=None,
                     expose_value=False, callback=_store, metavar="N",
                     help="--ray: run a log's task again up to N times when its worker dies "
                          "[default: 0].")(f)
    f = click.option("--ray", "ray", is_flag=False, flag_value="local", default=None,
                     expose_value=False, callback=_check_address, metavar="[ADDRESS]",
                     help="Audit the logs on Ray, one task per log: a local Ray for the run, "
                          "or ADDRESS of a cluster (auto, ray://host:10001). "
                          "Needs pip install 'fretc[ray]'.")(f)
    return f


def _check_address(ctx, param, value):
    if value is None:
        return None
    import importlib.util  # lazy: only for --ray (start-up time)

    if importlib.util.find_spec("ray") is None:
        # lazy: the audit engine is not loaded for --help
        from fretc.audit.fleet.ray import RAY_HINT

        raise click.UsageError(RAY_HINT, ctx=ctx)
    ok = (value in ("local", "auto") or value.startswith("ray://")
          or (":" in value and not os.path.exists(value) and "/" not in value))
    if not ok:
        raise click.BadParameter(
            f"{value!r} is not a Ray address (local, auto, ray://host:10001, host:6379); "
            "give the logs before --ray, or write --ray=ADDRESS", ctx=ctx, param=param)
    return _store(ctx, param, value)


def run_audits(plan: AuditPlan, paths: Sequence[str], jobs: int = 1,
               progress: LogProgress | None = None,
               ctx: click.Context | None = None) -> list[Any]:
    """The commands' audit of ``paths``: on Ray when ``--ray`` was given
    (:func:`ray_options`), else :func:`fretc.audit.audit_logs` with ``jobs`` processes.

    Raises :class:`FleetError` (exit code 2; 130 when interrupted) when Ray cannot be
    started or reached."""
    # lazy: the audit engine (numpy, mcap, rosbags) is loaded only when a command runs
    from fretc.audit import audit_logs

    opts = (ctx.meta.get(META) if ctx is not None else None) or {}
    if "ray" not in opts:
        return audit_logs(plan, paths, jobs=jobs, progress=progress)
    from fretc.audit.fleet.ray import RayUnavailable, audit_logs_ray  # lazy: --ray only
    try:
        return audit_logs_ray(plan, paths, address=opts["ray"],
                              retries=opts.get("retries") or 0, progress=progress)
    except RayUnavailable as exc:
        raise FleetError(str(exc)) from None
    except KeyboardInterrupt:
        err = FleetError("interrupted: the running Ray tasks were cancelled; no result was "
                         "written")
        err.exit_code = 130  # type: ignore[misc]  # (this error's own exit code)
        raise err from None


# ------------------------------------------------------------------ requirement sets
# The options and the reading shared by the commands that take requirement files and ask
# about the set as written (fretc check, fretc shield, fretc testgen): defined once here.


def names_of(text: str | None) -> list[str] | None:
    """The names of ``--inputs``/``--outputs`` (commas or blanks between them, a name that
    is no identifier in double quotes, as FRETish writes it); None for no option.

    Raises:
        click.BadParameter: a name that does not read (unclosed quotes)."""
    from fretc.fretish.files import split_names

    if text is None:
        return None
    try:
        return split_names(text)
    except ValueError as exc:
        raise click.BadParameter(str(exc)) from None


def io_options(inputs_help: str, outputs_help: str) -> Callable[[F], F]:
    """``--inputs A,B`` and ``--outputs C,D`` (read with :func:`names_of`), their help
    saying what the command does with them."""
    def decorate(f: F) -> F:
        f = click.option("--outputs", default=None, metavar="C,D", help=outputs_help)(f)
        return click.option("--inputs", default=None, metavar="A,B", help=inputs_help)(f)
    return decorate


def set_bindings_option(help_text: str) -> Callable[[F], F]:
    """``-b/--bindings FILE`` (one binding file) of a requirement set: what the command
    does with it (``help_text``), and the tick period its durations convert with where the
    files declare none (:func:`requirement_set`)."""
    return click.option(
        "-b", "--bindings", "bindings_file", type=click.Path(exists=True, dir_okay=False),
        default=None, metavar="FILE",
        help=help_text + " Its [tick] period (or tick topic's nominal_rate) is the "
             "requirements' where they declare no @tick_period; default: a binding file "
             "beside them, as fretc audit finds it.")


def budget_options(per: str) -> Callable[[F], F]:
    """``--budget``, ``--memory-budget`` and ``--query-cpu`` of ``fretc check``'s engines
    (:mod:`fretc.check.budget`), ``per`` what one budget covers (``"query"``, ``"game"``)."""
    from fretc.check.budget import DEFAULT_MEMORY, DEFAULT_QUERY_CPU, DEFAULT_WORK, MIN_MEMORY

    options = [
        click.option("--budget", type=click.IntRange(min=1), default=DEFAULT_WORK,
                     show_default=True, metavar="UNITS",
                     help=f"Work units per {per}: one unit is one BDD node of a set a fixed "
                          "point computes, or 10 of z3's resource count (rlimit); past it the "
                          "answer is unknown. Counted, not timed: the same answers on any "
                          "machine."),
        click.option("--memory-budget", type=click.IntRange(min=MIN_MEMORY),
                     default=DEFAULT_MEMORY, show_default=True, metavar="NODES",
                     help=f"BDD nodes per {per} (BuDDy's node table, about 20 bytes a node; "
                          "a BDD variable counts as 32, a term of z3's lasso encoding as 8); "
                          "past it the answer is unknown."),
        click.option("--query-cpu", type=FiniteRange(0, 1e7, min_open=True),
                     default=DEFAULT_QUERY_CPU, show_default=True, metavar="SECONDS",
                     help=f"CPU seconds a {per} may take: a safety net for the one step of a "
                          "fixed point that the work budget does not foresee (a BDD "
                          "operation cannot be metered); past it the answer is unknown and "
                          "says so."),
    ]

    def decorate(f: F) -> F:
        for opt in reversed(options):
            f = opt(f)
        return f
    return decorate


class RequirementSet:
    """Requirement files as ``fretc check``, ``fretc shield`` and ``fretc testgen`` read them
    (:func:`requirement_set`): ``as_written`` the entries as read, ``entries`` with a FRET
    export's literal constants and each one's tick period (those ``--only``/``--exclude``
    select), ``notes`` what a FRET export declares and no requirement uses, ``bindings`` the
    ``-b`` file read (None without), ``inputs``/``outputs`` the files' ``@inputs``/
    ``@outputs``, or a FRET export's Input and Output variables of ``--component`` (None
    when they declare none).

    Raises:
        InputError: ``--component`` names no component of a requirement, or (without it) a
            FRET export declares a variable an Input of one component and an Output of
            another, named with both (the set's inputs and outputs are then ambiguous)."""

    def __init__(self, as_written: list[Any], entries: list[Any], notes: list[str],
                 bindings: Any, component: str | None = None,
                 every: list[Any] | None = None, stream_use: str = "", bits: bool = False):
        self.as_written, self.entries, self.notes = as_written, entries, notes
        #: whether the boolean streams of booleans are read by their state bit
        #: (:func:`fretc.fretish.fret_variables.with_fret_definitions`' ``bits``)
        self.bits = bits
        self.bindings = bindings
        #: how the command reads a FRET stream variable, in its notes
        #: (:func:`fretc.fretish.fret_variables.unused`; "" a free variable)
        self.stream_use = stream_use
        self.component = component
        #: per requirement id, why it has no tick period (``defer_periods`` of
        #: :func:`requirement_set`): its FRET component is then not checked
        self.period_errors: dict[str, str] = {}
        self._own = entries
        if component is not None:  # (its declarations: every requirement's, selected or not)
            self._own = _of_component(every if every is not None else entries, component)

    def by_component(self) -> list[tuple[str, RequirementSet]]:
        """The set split as FRET checks a project (:mod:`fretc.check.fret_components`): per
        component its selected requirements, its own Inputs and Outputs and the notes on
        the variables they read, in the order the components first appear; empty when the
        files declare no FRET variable, name fewer than two components, or have a
        requirement that did not parse (the set is then checked whole, as before)."""
        from fretc.fretish.fret_variables import fret_declarations

        if any(e.requirement is None for e in self.entries) or not any(
                getattr(e, "variables", ()) for e in self.as_written):
            return []
        names = list(dict.fromkeys(e.requirement.component for e in self.entries))
        if len(names) < 2:
            return []
        written = {e.id: e for e in self.as_written}
        out = []
        for name in names:
            own = [e for e in self.entries if e.requirement.component == name]
            notes = fret_declarations([written[e.id] for e in own],
                                      stream_use=self.stream_use, bits=self.bits)[1]
            part = RequirementSet(self.as_written, own, notes, self.bindings, name,
                                  _of_component(self.as_written, name), self.stream_use,
                                  self.bits)
            part.period_errors = {e.id: self.period_errors[e.id] for e in own
                                  if e.id in self.period_errors}
            out.append((name, part))
        return out

    @property
    def inputs(self) -> list[str] | None:
        """The declared inputs (class docstring); read only when ``--inputs`` is not given.

        Raises:
            InputError: as the class docstring says."""
        if self.component is None:
            _one_side(self.entries)
        ins = [n for e in self._own for n in e.inputs]
        return list(dict.fromkeys(ins)) if ins else None

    @property
    def outputs(self) -> list[str] | None:
        """The declared outputs (class docstring); read only when ``--outputs`` is not
        given.

        Raises:
            InputError: as the class docstring says."""
        if self.component is None:
            _one_side(self.entries)
        outs = [n for e in self._own for n in e.outputs]
        return list(dict.fromkeys(outs)) if outs else None


def _one_side(entries: list[Any]) -> None:
    """Raise :class:`fretc.common.errors.InputError` when a FRET export declares a variable
    an Input of one component and an Output of another (FRET's variables are per component:
    the Safe-ROS stop request is the safety system's output and the interceptor's input)."""
    from fretc.common.errors import InputError

    sides: dict[str, dict[str, set[str]]] = {}
    for e in entries:
        for v in getattr(e, "variables", ()):
            if v.kind in ("Input", "Output"):
                sides.setdefault(v.name, {}).setdefault(v.kind, set()).add(v.component)
    both = [f"{name} is an Output of {', '.join(sorted(k['Output']))} and an Input of "
            f"{', '.join(sorted(k['Input']))}" for name, k in sides.items()
            if "Input" in k and "Output" in k]
    if both:
        raise InputError("FRET's export declares its variables per component: "
                         + "; ".join(both) + ". Give --component NAME to take one component's "
                         "inputs and outputs (or --inputs and --outputs)")


def selection_options(f: F) -> F:
    """``--component NAME``, ``--only IDS`` and ``--exclude IDS`` of a requirement set
    (:func:`requirement_set`)."""
    for opt in reversed((
        click.option("--component", default=None, metavar="NAME",
                     help="Take the inputs and outputs a FRET export declares for this "
                          "component (FRET's variables are per component)."),
        click.option("--only", default=None, metavar="IDS",
                     help="Only these requirements (ids, commas between them)."),
        click.option("--exclude", default=None, metavar="IDS",
                     help="Leave these requirements out (ids, commas between them).")),
    ):
        f = opt(f)
    return f


def _selected(entries: list[Any], only: str | None, exclude: str | None) -> list[Any]:
    """``entries`` with ``--only``/``--exclude`` applied (module docstring).

    Raises:
        InputError: an id no requirement has, or nothing left."""
    from fretc.common.errors import InputError

    ids = [e.id for e in entries]
    chosen = names_of(only) if only is not None else None
    dropped = names_of(exclude) or []
    unknown = [i for i in [*(chosen or []), *dropped] if i not in ids]
    if unknown:
        raise InputError(f"--only/--exclude name {', '.join(unknown)}: no requirement of that "
                         f"id (the files': {', '.join(ids)})")
    out = [e for e in entries if (chosen is None or e.id in chosen) and e.id not in dropped]
    if not out:
        raise InputError("--only/--exclude leave no requirement")
    return out


def requirement_set(files: Sequence[str], bindings_file: str | None, *,
                    component: str | None = None, only: str | None = None,
                    exclude: str | None = None,
                    tick_period: str | None = None, stream_use: str = "",
                    bits: bool = False, defer_periods: bool = False) -> RequirementSet:
    """Read requirement ``files`` (any format :func:`fretc.fretish.files.load_requirements`
    reads) with the ``-b`` binding file: each requirement's tick period is ``tick_period``
    (``--tick-period``, every requirement's, as in ``fretc audit``), else its file's
    ``@tick_period``, else the bindings' (``-b``, else the binding files beside the
    requirements, :func:`fretc.audit.discovery.discover_bindings`, read only when a
    requirement needs a period), never a duration in time units read as ticks
    (:mod:`fretc.signals.bindings.periods`); ``component`` (that component's requirements
    only), ``only``, ``exclude`` the options of :func:`selection_options`
    (:class:`RequirementSet`). Only the requirements selected need a period, and the notes
    on a FRET export's declarations are those of the variables they read (``stream_use``:
    how the command reads a FRET stream variable, :func:`fretc.fretish.fret_variables.unused`;
    ``bits``: a boolean stream of booleans read by its state bit, ``fretc check``'s and
    ``fretc shield``'s reading, :func:`fretc.fretish.fret_variables.with_fret_definitions`).
    ``defer_periods``: a requirement with no period known is kept, its error in
    :attr:`RequirementSet.period_errors` (``fretc check`` on a FRET project: that component
    not checked, the others checked).

    Raises:
        FretcError: a file or binding file that cannot be read, no period known for a
            duration in time units, an unknown id or component, a bad ``tick_period``, a
            FRET variable both a component's input and another's output without
            ``component`` (exit 2 through the command group)."""
    from pathlib import Path

    from fretc.common.errors import InputError
    from fretc.fretish.files import load_requirements
    from fretc.fretish.fret_variables import fret_declarations
    from fretc.signals.bindings.periods import time_unit_duration, with_periods

    override = period_option_value(tick_period)
    try:
        as_written = load_requirements([Path(p) for p in files], text_attribute=text_attribute())
    except OSError as exc:
        raise InputError(f"cannot read the requirements: {exc}") from None
    every = as_written
    chosen = as_written
    if component is not None:  # (that component's requirements only, as FRET checks one)
        every = chosen = _of_component(as_written, component)
    if only is not None or exclude is not None:
        chosen = _selected(chosen, only, exclude)
    entries, notes = fret_declarations(chosen, stream_use=stream_use, bits=bits)
    bindings, found = None, ""
    if bindings_file is not None:
        from fretc.signals.bindings.files import load_bindings

        bindings, found = load_bindings(bindings_file), "-b"
    elif override is None and any(e.tick_period is None and time_unit_duration(e)
                                  for e in entries):
        bindings, found = _beside(files)
    errors: dict[str, str] = {}
    try:
        entries = with_periods(entries, bindings, found, override)
    except InputError:
        if not defer_periods:
            raise
        entries, errors = _periods_each(entries, bindings, found)
    if bindings_file is None:
        bindings = None  # (found beside: its period only)
    rs = RequirementSet(as_written, entries, notes, bindings, component, every, stream_use,
                        bits)
    rs.period_errors = errors
    return rs


def _periods_each(entries: list[Any], bindings: Any,
                  found: str) -> tuple[list[Any], dict[str, str]]:
    """``entries`` each with its tick period as :func:`with_periods` gives it, one at a
    time: those it refuses kept as they are, ``{id: its error}`` beside them."""
    from fretc.common.errors import InputError
    from fretc.signals.bindings.periods import with_periods

    out, errors = [], {}
    for e in entries:
        try:
            [e] = with_periods([e], bindings, found)
        except InputError as exc:
            errors[e.id] = str(exc)
        out.append(e)
    return out, errors


def period_option_value(tick_period: str | None) -> Any:
    """``--tick-period`` (``"100 ms"``, ``"10 Hz"``; :func:`fretc.common.units.parse_duration`)
    as a :class:`fractions.Fraction` of seconds, None when not given.

    Raises:
        InputError: a value that is not a positive duration, naming the option."""
    if tick_period is None:
        return None
    from fractions import Fraction

    from fretc.common.errors import InputError
    from fretc.common.units import parse_duration

    try:
        return Fraction(parse_duration(tick_period), 1_000_000_000)
    except ValueError as exc:
        raise InputError(f"--tick-period: {exc}") from None


def entries_with_period(entries: list[Any], tick_period: str | None) -> list[Any]:
    """``entries`` (:class:`fretc.fretish.entry.RequirementEntry`) each with ``--tick-period``
    (:func:`period_option_value`) as its tick period; ``entries`` when it is not given.

    Raises:
        InputError: a ``tick_period`` that is not a positive duration."""
    import dataclasses

    period = period_option_value(tick_period)
    if period is None:
        return entries
    return [dataclasses.replace(e, tick_period=period) for e in entries]


#: ``--tick-period`` of the commands that read requirements outside an audit (check, shield,
#: testgen, compile, explain): a FRET export cannot declare ``@tick_period``
TICK_PERIOD_OPTION = click.option(
    "--tick-period", default=None, metavar="DURATION",
    help="The tick period durations in time units convert with, e.g. \"100 ms\" (overrides "
         "the files' @tick_period and the bindings'; the way to give a FRET export one).")


def _of_component(entries: list[Any], component: str) -> list[Any]:
    """The entries whose requirement is of ``component`` (FRET judges a component's
    requirements with that component's variables: its realizability table has a row per
    component). Raises :class:`fretc.common.errors.InputError` when none is, naming the
    components there are."""
    from fretc.common.errors import InputError

    own = [e for e in entries if e.requirement is not None
           and e.requirement.component == component]
    if not own:
        comps = sorted({e.requirement.component for e in entries if e.requirement is not None})
        raise InputError(f"--component {component}: no requirement of that component in the "
                         f"files (their components: {', '.join(comps)})")
    return own


def exit_on_compile_errors(files: Sequence[str], compiled: Sequence[Any],
                           also: Sequence[Any] = ()) -> None:
    """Print the error of every requirement of ``compiled`` and ``also`` (entries of
    :func:`fretc.compiler.build.compile_entries`; ``also``: others read beside them, such as
    ``--assume``'s) that could not be compiled, each naming its file:line:col, and exit 2
    if there is one, or if ``compiled`` is empty (no requirement in ``files``)."""
    bad = [c for c in [*compiled, *also] if c.error is not None]
    for c in bad:
        click.echo(shown(str(c.error)), err=True)
    if bad:
        sys.exit(2)
    if not compiled:
        click.echo(shown(f"error: no requirement in {', '.join(files)}"), err=True)
        sys.exit(2)


def _beside(files: Sequence[str]) -> tuple[Any, str]:
    """The binding file beside the requirement ``files`` whose period they take (module
    docstring of :mod:`fretc.signals.bindings.periods`), and how it was found; ``(None,
    "")`` when there is none.

    Raises:
        InputError: binding files beside them that give different periods."""
    from fretc.audit.discovery import discover_bindings
    from fretc.common.errors import InputError
    from fretc.common.units import format_period
    from fretc.signals.bindings.files import load_bindings
    from fretc.signals.bindings.periods import bindings_period

    found = [(p, load_bindings(p)) for p in discover_bindings(list(files))]
    periods = {p: t for p, b in found if (t := bindings_period(b)) is not None}
    with_period = [(p, b) for p, b in found if p in periods]
    if len(set(periods.values())) > 1:
        raise InputError("the binding files beside the requirements tick at different "
                         "periods (" + ", ".join(f"{p}: {format_period(t)}"
                                                 for p, t in periods.items())
                         + "): give the one to use with -b")
    if with_period:
        return with_period[0][1], f"beside the requirements: {with_period[0][0]}"
    return (found[0][1], f"beside the requirements: {found[0][0]}") if found else (None, "")


def requirement_inputs(paths: Sequence[str | os.PathLike[str]], what: str = "the requirement file"
                       ) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """``(files, folders)``: ``(what, file)`` for every requirement file ``paths`` name (a
    folder's files, as :func:`fretc.fretish.files.requirement_files` reads them; a Doorstop
    tree, read whole, is one input), and ``("the requirement folder", folder)`` for each
    other folder among ``paths``: the inputs and input folders that
    :func:`refuse_outputs_over_inputs` compares a command's outputs with.

    Raises:
        FretishFileError: a path that is neither a file nor a folder."""
    from fretc.common.outputs import same_path
    from fretc.fretish.files import requirement_files

    files = [(what, f) for f in requirement_files([os.fspath(p) for p in paths])]
    folders = [("the requirement folder", os.fspath(p)) for p in paths
               if os.path.isdir(p) and not any(same_path(p, f) for _, f in files)]
    return files, folders


def refuse_outputs_over_inputs(outputs: Sequence[tuple[str, Any]],
                               inputs: Sequence[tuple[str, Any]],
                               out_folders: Sequence[tuple[str, Any]] = (),
                               in_folders: Sequence[tuple[str, Any]] = ()) -> None:
    """Refuse, before anything is written, an output that is one of the command's inputs:
    each output file of ``outputs`` (``(what, path)``, a path None or ``"-"`` skipped) that
    resolves to an input of ``inputs`` (links followed, a hard link by its inode) or lies
    inside an input folder read whole (a Doorstop tree, a rosbag2 folder), as
    :func:`fretc.common.outputs.refuse_replacing_inputs` decides; and each output folder of
    ``out_folders`` that is itself an input folder of ``in_folders`` (a folder the command
    reads the files of: ``fretc testgen reqs/ -o reqs``, the written files would sit among
    the inputs). An output folder inside an input folder is not refused: the files of a
    folder are read, not its sub-folders.

    Raises:
        OutputError: the first output that is an input (exit 2 through the command group,
            naming both)."""
    from fretc.common.outputs import refuse_replacing_inputs, same_path

    refuse_replacing_inputs(outputs, inputs)
    ins = [(w, os.fspath(p)) for w, p in in_folders if p is not None]
    for what, folder in out_folders:
        if folder is not None:
            refuse_replacing_inputs([(what, folder)],
                                    [(w, p) for w, p in ins if same_path(folder, p)][:1])


def refuse_folder_over_inputs(output: str, requirements: Sequence[str],
                              bindings: Sequence[str], space_path: str) -> None:
    """``fretc estimate`` and ``fretc falsify``: the output folder ``-o`` (which must be new
    or empty) is none of the inputs (the requirements, ``./requirements`` by default, the
    binding files, the space) and not a folder of requirements or bindings read.

    Raises:
        OutputError: it is (:func:`refuse_outputs_over_inputs`)."""
    named = list(requirements) or (["requirements"] if os.path.isdir("requirements") else [])
    files, folders = requirement_inputs(named)
    folders += [("the binding folder", b) for b in bindings if os.path.isdir(b)]
    refuse_outputs_over_inputs(
        [("-o", output)], files + [("the binding file", b) for b in bindings
                                   if not os.path.isdir(b)] + [("--space", space_path)],
        [("-o", output)], folders)
