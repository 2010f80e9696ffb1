"""The ``fretc`` command (click): the group and the registration of its sub-commands, one
module per sub-command in this folder (shared options: :mod:`fretc.cli.options`).

``fretc FILE... --emit ltl|monitor|psl`` compiles requirement files (the default command,
``fretc compile``: :mod:`fretc.cli.compile`); ``fretc audit`` checks recorded runs
(:mod:`fretc.cli.audit`); ``fretc report`` writes the traceability report (:mod:`fretc.cli.report`);
``fretc check`` (:mod:`fretc.cli.check`), ``fretc inspect`` (:mod:`fretc.cli.inspect`), ``fretc
watch`` and ``fretc replay`` (:mod:`fretc.cli.watch`), ``fretc export`` (:mod:`fretc.cli.export`),
``fretc estimate`` (:mod:`fretc.cli.estimate`). Exit codes: 0 success, 1 a requirement
failed (or, for ``audit``, a violation), 2 usage or input errors (every
:class:`fretc.common.errors.FretcError` that reaches the group), 3 an incomplete audit, 4 an
internal error (a generated monitor that is not valid: nothing is written), 5 a probability
requirement undecided (too few runs: ``audit``, ``estimate``).
"""

from __future__ import annotations

import os
import sys

# numpy's OpenBLAS starts a thread per core when numpy is imported; fretc makes no BLAS call
# (no matrix product, no linalg), and those threads' start cost a command 0.1 s to 0.2 s of
# CPU on a 2-core machine. One thread unless the user chose otherwise (OpenBLAS's own
# variable; set before anything imports numpy).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import click

from fretc.common.errors import FretcError, error_text

from fretc.cli.compile import compile_cmd
from fretc.cli.options import shown


class _DefaultGroup(click.Group):
    """A group whose first argument, when it is not a sub-command, goes to ``compile``
    (so ``fretc requirements/r1.fret --emit ltl`` works as the users wrote it).

    The optional sub-commands (:func:`_register_optional`) are attached on first need: not
    when the first argument is a requirement file (a path with a folder or a ``.fret`` /
    ``.json`` name, which no sub-command is called), so ``fretc FILE`` does not import the
    audit and report machinery (start-up time); a named sub-command imports only its own
    module (``fretc audit`` does not import ``fretc report``'s)."""

    _optional_registered = False

    def _ensure_optional(self, name: str | None = None) -> None:
        if _DefaultGroup._optional_registered:
            return
        if name in _OPTIONAL:
            if name not in self.commands:
                _register_one(name)
            return
        _DefaultGroup._optional_registered = True
        _register_optional()

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h",
                                                                     "--version"):
            if not _names_a_file(args[0]):
                self._ensure_optional(args[0])
            if args[0] not in self.commands:
                args = ["compile"] + list(args)
        return super().parse_args(ctx, args)

    def get_command(self, ctx, cmd_name):
        if cmd_name not in self.commands:
            self._ensure_optional(cmd_name)
        return super().get_command(ctx, cmd_name)

    def list_commands(self, ctx):
        self._ensure_optional()
        return super().list_commands(ctx)

    def invoke(self, ctx):
        """Run the sub-command; an input error of any stage (:class:`FretcError`) that it
        does not report itself is printed here (:func:`fretc.common.errors.error_text`, control
        characters escaped) with exit code 2. Anything else that escapes (a defect of fretc:
        a RecursionError, an OverflowError, ...) is an internal error: one line naming it and
        asking for a report, exit code 4, never a traceback with exit 1 (the code of
        "violated"); ``FRETC_TRACEBACK=1`` shows the traceback."""
        try:
            return super().invoke(ctx)
        except FretcError as exc:
            click.echo(shown(error_text(exc)), err=True)
            ctx.exit(2)
        except (click.exceptions.Exit, click.ClickException, click.Abort, SystemExit,
                KeyboardInterrupt):
            raise
        except BrokenPipeError:
            # the reader of the output went away (``fretc inspect LOG | head``): the usual
            # end of a Unix filter, exit 141 (128 + SIGPIPE) as a shell reports it
            _quiet_stdout()
            ctx.exit(141)
        except Exception as exc:  # noqa: BLE001 - the last line of defence
            if os.environ.get("FRETC_TRACEBACK"):
                raise
            click.echo(shown(f"internal error: {type(exc).__name__}: {exc}".splitlines()[0])
                       + " (please report it with the command and its inputs; "
                       "FRETC_TRACEBACK=1 shows the traceback)", err=True)
            ctx.exit(4)


def _quiet_stdout() -> None:
    """Point stdout at /dev/null so that Python's flush at exit does not fail again on the
    closed pipe."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def _names_a_file(arg: str) -> bool:
    """Can ``arg`` only be a requirement file (never a sub-command name)?"""
    return "/" in arg or os.sep in arg or arg.lower().endswith((".fret", ".json", ".reqif",
                                                                       ".reqifz"))


@click.group(cls=_DefaultGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="fretc")
def main() -> None:
    """fretc: FRETish requirements to FRET's LTL, runtime monitors and AJPF properties, and
    audits of recorded robot runs against them."""


main.add_command(compile_cmd, "compile")


#: The sub-commands other than ``compile``: name -> (module of this package, its command).
_OPTIONAL = {"audit": ("audit", "audit_cmd"), "check": ("check", "check_cmd"),
             "falsify": ("falsify", "falsify_cmd"),
             "estimate": ("estimate", "estimate_cmd"), "inspect": ("inspect", "inspect_cmd"),
             "report": ("report", "report_cmd"), "watch": ("watch", "watch_cmd"),
             "export": ("export", "export_cmd"), "simulate": ("simulate", "simulate_cmd"),
             "lsp": ("lsp", "lsp_cmd"), "explain": ("explain", "explain_cmd"),
             "distinguish": ("distinguish", "distinguish_cmd"),
             "testgen": ("testgen", "testgen_cmd"), "testrun": ("testrun", "testrun_cmd"),
             "shield": ("shield", "shield_cmd"),
             "shield-replay": ("shield_replay", "shield_replay_cmd"),
             "ajpf": ("ajpf", "ajpf_cmd"),
             "qualify": ("qualify", "qualify_cmd"),
             "ltlsim": ("ltlsim", "ltlsim_cmd"),
             "replay": ("watch", "replay_cmd")}


def _register_one(name: str) -> None:
    """Attach the sub-command ``name`` (a key of :data:`_OPTIONAL`), importing its module."""
    import importlib

    module, attr = _OPTIONAL[name]
    main.add_command(getattr(importlib.import_module(f"{__package__}.{module}"), attr), name)


def _register_optional() -> None:
    """Attach the sub-commands other than ``compile``. Called on first need by
    :class:`_DefaultGroup`, not at import: ``fretc FILE`` does not need them (start-up);
    lazy: their modules load rich and the report machinery (start-up time)."""
    for name in _OPTIONAL:
        if name not in main.commands:
            _register_one(name)


if __name__ == "__main__":  # pragma: no cover
    main()
