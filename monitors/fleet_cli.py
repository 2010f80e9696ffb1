"""The ``--ray [ADDRESS]`` and ``--retries N`` options of ``fretc audit`` and ``fretc report``
(:mod:`monitors.fleet` runs them). Only click is imported here, so the CLI starts fast."""

from __future__ import annotations

import importlib.util
import os

import click

__all__ = ["ray_options", "META", "RAY_HINT", "FleetError"]

#: How to get Ray (printed when ``--ray`` is used without it).
RAY_HINT = "--ray needs Ray: pip install 'fretc[ray]' (or pip install 'ray>=2.40')"
#: Key of the options in the click context's ``meta``.
META = "fretc.fleet"


class FleetError(click.ClickException):
    """Ray cannot be started or reached: printed as ``Error: ...``, exit code 2."""

    exit_code = 2


def _store(ctx, param, value):
    if value is not None:
        ctx.meta.setdefault(META, {})[param.name] = value
    return value


def ray_options(f):
    """``--ray [ADDRESS]`` and ``--retries N`` (values kept in the click context; read by
    :func:`run_audits`), for ``fretc audit`` and ``fretc report``."""
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
    if importlib.util.find_spec("ray") is None:
        raise click.UsageError(RAY_HINT, ctx=ctx)
    ok = (value in ("local", "auto") or value.startswith("ray://")
          or (":" in value and not os.path.exists(value) and "/" not in value))
    if not ok:
        raise click.BadParameter(
            f"{value!r} is not a Ray address (local, auto, ray://host:10001, host:6379); "
            "give the logs before --ray, or write --ray=ADDRESS", ctx=ctx, param=param)
    return _store(ctx, param, value)


