"""The ``fretc`` command (click): the group and the registration of its sub-commands, one
module per sub-command in this folder (shared options: :mod:`fretc.options`).

``fretc FILE... --emit ltl|monitor|psl`` compiles requirement files (the default command,
``fretc compile``: :mod:`fretc.compile`); ``fretc audit`` checks recorded runs
(:mod:`fretc.audit`); ``fretc report`` writes the traceability report (:mod:`fretc.report`);
``fretc check`` (:mod:`fretc.check`), ``fretc inspect`` (:mod:`fretc.inspect`), ``fretc
watch`` and ``fretc replay`` (:mod:`fretc.watch`). Exit codes: 0 success, 1 a requirement
failed (or, for ``audit``, a violation), 2 usage or input errors (every
:class:`common.errors.FretcError` that reaches the group), 3 an incomplete audit, 4 an
internal error (a generated monitor that is not valid: nothing is written).
"""

from __future__ import annotations

import atexit
import gc
import os

# Start-up time. The imports below make tens of thousands of objects (modules, classes,
# functions) that live until the process ends. Python's cyclic garbage collector would scan
# them as they are made, again at each later collection, and once more at exit, to free
# nothing: the collector is paused while they load, then they are moved to its permanent
# generation (gc.freeze: still freed by reference counting, never rescanned) and the
# collector is put back as it was. Together with _freeze_if_paused, a few per cent of the
# CPU time of `fretc r1.fret --emit ltl`. The price:
# a reference cycle that is already garbage when fretc.cli is first imported is never
# freed (bounded: only what exists at that moment; objects made later are collected as
# before).
_GC_WAS_ENABLED = gc.isenabled()
gc.disable()
try:
    import click

    from common.errors import FretcError, error_text

    from .compile import compile_cmd
    from .options import shown
finally:
    gc.freeze()
    if _GC_WAS_ENABLED:
        gc.enable()


def _freeze_if_paused() -> None:
    """At exit (``atexit``): when the command left the collector paused (``--emit ltl``
    does, :mod:`fretc.compile`: its objects are acyclic and live until the end), move
    everything to the permanent generation so the interpreter's final collection does not
    scan the run's objects (about 1% of a thousand requirements' CPU time). A command
    that keeps the collector running (the audit, the other emits) is left as it is."""
    if not gc.isenabled():
        gc.freeze()


atexit.register(_freeze_if_paused)


class _DefaultGroup(click.Group):
    """A group whose first argument, when it is not a sub-command, goes to ``compile``
    (so ``fretc requirements/r1.fret --emit ltl`` works as the users wrote it).

    The optional sub-commands (:func:`_register_optional`) are attached on first need: not
    when the first argument is a requirement file (a path with a folder or a ``.fret`` /
    ``.json`` name, which no sub-command is called), so ``fretc FILE`` does not import the
    audit and report machinery (start-up time)."""

    _optional_registered = False

    def _ensure_optional(self) -> None:
        if not _DefaultGroup._optional_registered:
            _DefaultGroup._optional_registered = True
            _register_optional()

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h",
                                                                     "--version"):
            if not _names_a_file(args[0]):
                self._ensure_optional()
            if args[0] not in self.commands:
                args = ["compile"] + list(args)
        return super().parse_args(ctx, args)

    def get_command(self, ctx, cmd_name):
        if cmd_name not in self.commands:
            self._ensure_optional()
        return super().get_command(ctx, cmd_name)

    def list_commands(self, ctx):
        self._ensure_optional()
        return super().list_commands(ctx)

    def invoke(self, ctx):
        """Run the sub-command; an input error of any stage (:class:`FretcError`) that it
        does not report itself is printed here (:func:`common.errors.error_text`, control
        characters escaped) with exit code 2."""
        try:
            return super().invoke(ctx)
        except FretcError as exc:
            click.echo(shown(error_text(exc)), err=True)
            ctx.exit(2)


def _names_a_file(arg: str) -> bool:
    """Can ``arg`` only be a requirement file (never a sub-command name)?"""
    return "/" in arg or os.sep in arg or arg.lower().endswith((".fret", ".json"))


@click.group(cls=_DefaultGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="fretc")
def main():
    """fretc: FRETish requirements to FRET's LTL, runtime monitors and AJPF properties, and
    audits of recorded robot runs against them."""


main.add_command(compile_cmd, "compile")


def _register_optional() -> None:
    """Attach the sub-commands other than ``compile``. Called on first need by
    :class:`_DefaultGroup`, not at import: ``fretc FILE`` does not need them (start-up)."""
    # lazy: these modules load rich and the report machinery (start-up time)
    from .audit import audit_cmd
    from .check import check_cmd
    from .inspect import inspect_cmd
    from .report import report_cmd
    from .watch import register as register_watch

    main.add_command(audit_cmd, "audit")
    main.add_command(check_cmd, "check")
    main.add_command(inspect_cmd, "inspect")
    main.add_command(report_cmd, "report")
    register_watch(main)


if __name__ == "__main__":  # pragma: no cover
    main()
