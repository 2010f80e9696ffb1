"""Option definitions shared by the ``fretc`` commands, and the click glue around the audit.

``audit_input_options`` (what to audit and how) and ``ray_options`` (``--ray [ADDRESS]``,
``--retries N``) decorate ``fretc audit``, ``fretc report`` and ``fretc watch``;
:func:`audit_config` turns their values into a :class:`fretc.audit.AuditConfig` and
:func:`run_audits` runs the audit locally or on Ray (:mod:`fretc.audit.fleet.ray`) as the options
say. Only click is imported at module level, so the command starts fast; the engine loads
on first use.
"""

from __future__ import annotations

import math
import os
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
           "run_audits", "META", "FleetError", "shown", "FiniteRange", "statistics_options"]


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


#: Key of ``--max-entities``' value in the click context's ``meta``.
MAX_ENTITIES_META = "fretc.max_entities"

#: ``--max-entities N``: entities of one per-entity requirement judged per log
MAX_ENTITIES_OPTION = click.option(
    "--max-entities", type=click.IntRange(min=1), default=None, metavar="N",
    expose_value=False,
    callback=lambda ctx, _p, v: ctx.meta.__setitem__(MAX_ENTITIES_META, v) if v else None,
    help="Judge at most N entities of one per-entity requirement per log (docs/bindings.md, "
         "\"One verdict per entity\"); past it, an error verdict names the rest. Default: "
         "1,000,000.")


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
                       max_entities=_max_entities())


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
