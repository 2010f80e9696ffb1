"""``fretc compile`` (also ``fretc FILE...``, the default command): requirement files to
FRET's LTL and PCTL (``--emit ltl``, text or ``--json``), Python runtime monitors (``--emit
monitor``), AJPF properties (``--emit psl``), PRISM properties (``--emit prism``), C99
monitors (``--emit c -o DIR``, :mod:`fretc.cli.emit_c`) or R2U2's C2PO specifications
(``--emit c2po``), CoCoSpec contracts for Kind 2 (``--emit cocospec``) or Ogma's FRET
component specifications (``--emit ogma``; both :mod:`fretc.cli.emit_c`).

Exit codes: 0 success, 1 a requirement failed, 2 usage or input errors, 4 an internal error
(a generated monitor that is not valid: nothing is written). Only click and the standard
library are imported at module level: ``fretc FILE --emit ltl`` loads the compiler, not
numpy, mcap, Jinja2 or Spot.
"""

from __future__ import annotations

import sys

import click
from collections.abc import Callable, Sequence
from typing import Any, TYPE_CHECKING

from fretc.common.textsafe import visible

from fretc.cli.options import (TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION, entries_with_period,
                               period_option_value, text_attribute)
from fretc.cli.options import shown as _shown

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["compile_cmd"]


def _entries(paths, tick_period: str | None = None) -> list:
    """The :class:`fretc.fretish.files.RequirementEntry` list of ``paths``, parsed, each with
    ``tick_period`` (``--tick-period``) as its period when given (an unreadable file: its
    error printed, exit code 2; a :class:`fretc.common.errors.FretishError` of a file or a
    bad ``--tick-period`` goes to the command group's handler: printed, exit code 2)."""
    from fretc.fretish.files import load_requirements  # lazy: the parser only when a command compiles

    period_option_value(tick_period)  # (a bad value before any file is read)
    try:
        entries = load_requirements(list(paths), text_attribute=text_attribute())
    except OSError as exc:
        click.echo(_shown(f"error: {exc}"), err=True)
        sys.exit(2)
    return entries_with_period(entries, tick_period)


def _load(paths, tick_period: str | None = None, definitions: bool = False,
          streams: bool = False, stream_use: str = "") -> list:
    """The compiled requirements of ``paths`` (:func:`_entries`, then the compiler). With
    ``definitions`` (the runtime monitors: ``--emit monitor``, ``c``, ``c2po``), the
    Internal variables and modes a FRET export defines are their definitions, as FRET's
    own monitors (Ogma's Copilot streams) compute them from the variables they read: each
    said once on stderr, with those kept as inputs and why
    (:func:`fretc.fretish.fret_variables.fret_declarations`); with ``streams`` too
    (``monitor``, ``c``), a definition that reads itself through ``pre`` is computed by
    the monitor tick by tick (:mod:`fretc.fretish.fret_streams`), its inputs the variables
    it reads; ``stream_use`` (``c2po``): what the notes say of a stream variable kept an
    input instead (:func:`fretc.fretish.fret_variables.unused`)."""
    # lazy: the compiler (Lark tables, Spot) only when a command compiles
    from fretc.compiler.build import compile_entries

    entries = _entries(paths, tick_period)
    if definitions:
        from fretc.fretish.fret_variables import fret_declarations

        entries, notes = fret_declarations(entries, use=_MONITOR_USE, streams=streams,
                                           stream_use=stream_use)
        for n in notes:
            click.echo(_shown(f"note: {n}"), err=True)
    return compile_entries(entries)


#: how a runtime monitor uses a FRET definition (the notes of :func:`_load`)
_MONITOR_USE = "in the monitor (its inputs are the variables the definition reads)"

#: what ``--emit c2po``'s notes say of a stream variable (R2U2's specifications keep no
#: state but their temporal operators': a real number held from tick to tick is no formula)
_C2PO_STREAM_USE = ("an input signal of the C2PO specification: R2U2 keeps no stream's "
                    "state, so the trace R2U2 reads must carry the definition's values tick "
                    "by tick (fretc audit and fretc's --emit monitor and --emit c monitors "
                    "compute them from the variables it reads)")


@click.command("compile")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--emit", type=click.Choice(["ltl", "monitor", "psl", "prism", "c", "c2po",
                                          "cocospec", "ogma"]),
              default="ltl", show_default=True,
              help="What to produce: FRET's LTL (and PCTL), Python monitors, AJPF properties, "
                   "PRISM properties (FRET's bounds at each trigger), C99 monitors with a CSV "
                   "runner (-o DIR), R2U2's C2PO specifications, CoCoSpec contracts for "
                   "Kind 2 (one .lus per component), or Ogma's FRET component "
                   "specifications (one .json per component).")
@click.option("--json", "as_json", is_flag=True, help="ltl: print a JSON list instead of text.")
@click.option("-o", "--output", type=click.Path(), default=None,
              help="monitor/psl/prism/c2po: output file (one input) or directory; "
                   "cocospec/ogma: file (one component) or directory; default: stdout.")
@click.option("--psl-map", type=click.Path(exists=True), default=None,
              help="psl: TOML mapping of variables to AJPF beliefs, percepts and actions.")
@click.option("--split", is_flag=True,
              help="c: one header and source per requirement instead of one per file.")
@TICK_PERIOD_OPTION
@TEXT_ATTRIBUTE_OPTION
def compile_cmd(files: tuple[str, ...], emit: str, as_json: bool, output: str | None,
                psl_map: str | None, split: bool, tick_period: str | None) -> None:
    """Compile requirement FILES (.fret, FRET JSON exports, .reqif/.reqifz, Doorstop
    trees)."""
    if emit == "ltl":
        if as_json:
            texts, failed = _ltl_json_texts(files, tick_period)
            for c in failed:
                click.echo(_shown(str(c.error)), err=True)
            _write_json_list(sys.stdout, texts)
            sys.exit(1 if failed else 0)
    compiled = _load(files, tick_period, definitions=emit in ("monitor", "c", "c2po"),
                     streams=emit in ("monitor", "c"),
                     stream_use=_C2PO_STREAM_USE if emit == "c2po" else "")
    if not compiled:
        _no_requirements(files)
    failed = [c for c in compiled if c.error is not None]
    for c in failed:
        click.echo(_shown(str(c.error)), err=True)
    if emit == "ltl":
        _emit_ltl(compiled)  # text; --json took _ltl_json_texts above
    elif emit == "monitor":
        from fretc.compiler.codegen import build_monitor_modules  # lazy: Jinja2 and Spot
        internal: list = []
        modules = build_monitor_modules(compiled, internal).values()
        outputs = {m.name: m.text for m in modules}
        for exc in internal:  # never exit 0 with a monitor that is not valid
            click.echo(str(exc), err=True)
        if internal:
            sys.exit(4)  # internal error: not audit's 3 (incomplete)
        _check_output(outputs, output, ".py")
        _write_outputs(outputs, output, ".py", _inputs(files, psl_map))
        reported = {c.id for c in failed}  # their error is printed above
        for m in modules:
            for rid, reason in m.skipped.items():
                if rid not in reported:
                    click.echo(_shown(f"skipped {rid} ({m.name}): {reason}".replace(
                        "\n", " ")), err=True)
    elif emit == "c":
        from fretc.cli.emit_c import write_c
        write_c(compiled, output, split, _inputs(files, psl_map))
    elif emit == "c2po":
        from fretc.cli.emit_c import write_c2po
        inputs = _inputs(files, psl_map)
        write_c2po(compiled, output, _check_output,
                   lambda outs, path, suffix: _write_outputs(outs, path, suffix, inputs))
    elif emit in ("cocospec", "ogma"):
        from fretc.cli.emit_c import write_exports
        inputs = _inputs(files, psl_map)
        write_exports(emit, compiled, output, _check_output,
                      lambda outs, path, suffix: _write_outputs(outs, path, suffix, inputs))
    elif emit == "prism":
        from fretc.compiler.prism import emit_prism  # lazy: only for prism
        refused: list = []
        outputs = emit_prism(compiled, refused)
        _check_output(outputs, output, ".props")
        _write_outputs(outputs, output, ".props", _inputs(files, psl_map))
        for stem, rid, why in refused:
            click.echo(_shown(f"skipped {rid} ({stem}.props): {why}"), err=True)
    elif emit == "psl":
        from fretc.compiler.ajpf import emit_psl  # lazy: only for psl
        outputs = emit_psl(compiled, mapping_path=psl_map)  # AjpfError: the group's handler
        _check_output(outputs, output, ".psl")
        _write_outputs(outputs, output, ".psl", _inputs(files, psl_map))
    sys.exit(1 if failed else 0)


def _no_requirements(files) -> None:
    click.echo(f"error: no requirements in {', '.join(files)} (empty or only comments)",
               err=True)
    sys.exit(2)


def _ltl_json_texts(paths, tick_period: str | None = None) -> tuple:
    """``(texts, failed)`` of ``--emit ltl --json``: per requirement of ``paths``, in order,
    its text in the JSON list (:func:`ltl_json_item`), and the compiled requirements that
    failed (their errors are printed before the list). Each requirement is compiled and
    written before the next: its entry (the parsed sentence), formula trees and printed
    forms are dropped as soon as its text is made (a failed one is kept for its error), so
    the run keeps the texts, not a thousand requirements' trees (a third of the peak
    memory of a thousand requirements). Errors, exit codes and texts are those of
    :func:`_load` then :func:`ltl_json`; ``tick_period`` as there."""
    from fretc.compiler.build import compile_entry

    entries = _entries(paths, tick_period)
    if not entries:
        _no_requirements(paths)
    item = ltl_json_item()
    texts: list = []
    failed: list = []
    for i, e in enumerate(entries):
        entries[i] = None  # the list's reference: freed with the last one below
        c = compile_entry(e)
        if c.error is not None:
            failed.append(c)
        texts.append(item(c))
        del c, e  # not held while the next one compiles
    return texts, failed


#: items of the JSON list written per write call by :func:`_write_json_list` (about 80 kB
#: of text for requirements of a generated sentence)
_WRITE_BATCH = 32


def _write_json_list(out, texts: list) -> None:
    """Write the JSON list of the item ``texts`` (:func:`ltl_json_item`) and a newline to
    the text stream ``out``, as ``out.write(ltl_json(...) + "\n")`` writes it, in batches of
    :data:`_WRITE_BATCH` items: no text of the whole list is made (joined, then copied with
    its newline, then encoded: three copies of a 2.6 MB text for a thousand requirements).
    ``click.echo`` is not used: it would scan the text for ANSI escapes to strip, and
    JSON's text is printable ASCII (``ensure_ascii`` escapes every control character)."""
    if not texts:
        out.write("[]\n")
    else:
        sep = "[\n  "
        for i in range(0, len(texts), _WRITE_BATCH):
            out.write(sep)
            out.write(",\n  ".join(texts[i:i + _WRITE_BATCH]))
            sep = ",\n  "
        out.write("\n]\n")
    out.flush()


class _NotPlain(Exception):
    """A value :func:`json_indent2` leaves to :func:`json.dumps`."""


def _string_encoder():
    """``json``'s C string escaper (``ensure_ascii=True``, the default of ``json.dumps``),
    taken from ``_json`` without importing the ``json`` package (its decoder and scanner:
    start-up time); ``json.encoder``'s own choice where ``_json`` is missing."""
    try:
        from _json import encode_basestring_ascii
    except ImportError:  # pragma: no cover - CPython always has _json
        from json.encoder import encode_basestring_ascii
    return encode_basestring_ascii


def _indent2_writer(enc):
    """``(go, parts)``: ``go(value, pad)`` appends the ``json.dumps(value, indent=2)`` text
    of ``value`` nested at ``pad`` (a newline and the indentation of its line) to
    ``parts``; raises :class:`_NotPlain` for a value outside the plain shapes of
    :func:`json_indent2`. ``enc`` is the string escaper (:func:`_string_encoder`)."""
    parts: list = []
    add = parts.append
    layouts: dict = {}
    scalars = {None: "null", True: "true", False: "false"}  # 1 == True: looked up by type

    def layout(keys: tuple, pad: str) -> tuple:
        lay = _layout(enc, keys, pad)
        layouts[(keys, pad)] = lay
        return lay

    def go(o, pad: str) -> None:
        t = type(o)
        if t is str:
            add(enc(o))
        elif o is None or t is bool:
            add(scalars[o])
        elif t is int:
            add(int.__repr__(o))
        elif t is list:
            if not o:
                add("[]")
                return
            inner = pad + "  "
            for x in o:
                if type(x) is not str:
                    break
            else:  # all strings: one join
                add("[" + inner + ("," + inner).join(map(enc, o)) + pad + "]")
                return
            sep = "[" + inner
            for x in o:
                add(sep)
                go(x, inner)
                sep = "," + inner
            add(pad + "]")
        elif t is dict:
            if not o:
                add("{}")
                return
            keys = tuple(o)
            lay = layouts.get((keys, pad))
            if lay is None:
                lay = layout(keys, pad)
            heads, inner, close = lay
            for head, v in zip(heads, o.values()):
                t = type(v)
                if t is str:
                    add(head)
                    add(enc(v))
                elif v is None or t is bool:
                    add(head + scalars[v])
                elif t is int:
                    add(head + int.__repr__(v))
                else:
                    add(head)
                    go(v, inner)
            add(close)
        else:
            raise _NotPlain

    return go, parts


def _layout(enc, keys: tuple, pad: str) -> tuple:
    """``(heads, inner, close)`` of a dict with string ``keys`` nested at ``pad``: per key
    the text before its value (``{`` or ``,``, the indentation, the quoted key, ``: ``),
    the values' indentation and the closing text; :class:`_NotPlain` for a key that is
    not a string."""
    inner = pad + "  "
    for k in keys:
        if type(k) is not str:
            raise _NotPlain
    heads = tuple(("{" if i == 0 else ",") + inner + enc(k) + ": "
                  for i, k in enumerate(keys))
    return heads, inner, pad + "}"


def json_indent2(obj: Any) -> str:
    """``json.dumps(obj, indent=2)``, the same text, for dicts with string keys, lists,
    strings, ints, booleans and None (anything else: ``json.dumps`` itself). The standard
    library's C encoder only serves ``indent=None``; its Python one is a tenth of the time
    of ``--emit ltl --json`` on a thousand requirements.

    A dict is written from a layout computed once per (key tuple, depth): the quoted keys
    with their separators and indentation, so a list of same-shaped objects costs one
    escape per string value and one join; a list whose items are all strings is one join.
    Any other shape takes the general recursive path; a value neither handles (a float, a
    non-string key, nesting deeper than the recursion limit) gives ``json.dumps``'s text.
    :func:`ltl_json` writes ``--emit ltl --json``'s list without building the dicts."""
    go, parts = _indent2_writer(_string_encoder())
    try:
        go(obj, "\n")
    except (_NotPlain, RecursionError):
        import json  # lazy: only for values outside the plain shapes
        return json.dumps(obj, indent=2)
    return "".join(parts)


def ltl_json(compiled: Sequence[Compiled]) -> str:
    """``json_indent2([c.to_json() for c in compiled])``, the same text, written in one pass:
    each requirement's text is :func:`ltl_json_item`'s, the list around them as
    ``json.dumps(..., indent=2)`` writes it."""
    if not compiled:
        return "[]"
    return "[\n  " + ",\n  ".join(map(ltl_json_item(), compiled)) + "\n]"


def ltl_json_item() -> Callable[[Compiled], str]:
    """``item(compiled) -> str``: the text of ``compiled.to_json()`` as an item of
    :func:`ltl_json`'s list (``json.dumps(..., indent=2)``'s text nested one level: every
    line after the first indented by two more spaces), for one
    :class:`fretc.compiler.build.Compiled`.

    A requirement that formalized is one join of the texts between its values, made once
    from :data:`fretc.compiler.build.FORMALIZED_KEYS` (its layout as :func:`json_indent2` makes
    it), and :meth:`fretc.compiler.build.Compiled.json_values`, the strings escaped by ``json``'s C
    escaper; its five printed forms come escaped in one piece from its template where
    there is one (:meth:`fretc.compiler.build.Compiled.json_forms`). Any other requirement, or a
    value of another type than those :meth:`~fretc.compiler.build.Compiled.json_values`
    documents, takes :func:`json_indent2`'s general path, and a value that path cannot
    write ``json.dumps(value, indent=2)`` nested one level (JSON strings escape newlines,
    so its only newlines are its layout's)."""
    from fretc.compiler.build import FORMALIZED_KEYS

    enc = _string_encoder()
    go, parts = _indent2_writer(enc)
    heads, inner, close = _layout(enc, FORMALIZED_KEYS, "\n  ")
    # ft, ft_inf, pt, ft_spot, ft_inf_spot: one field of the format, the texts between them
    # given to json_forms
    ft = FORMALIZED_KEYS.index("ft")
    seps = heads[ft + 1:ft + 5]
    s0, s1, s2, s3 = seps
    # the text before each written value (the five forms are one), in one join per
    # requirement (a % format would scan these texts character by character)
    (h_id, h_text, h_source, h_line, h_parent, h_rationale, h_key, h_forms, h_vars,
     h_vars_fret, h_ticks, h_warnings, h_causal) = heads[:ft + 1] + heads[ft + 5:]
    li = inner + "  "  # a list value's items
    lsep = "," + li
    scalars = {None: "null", True: "true", False: "false"}

    def item(c) -> str:
        values = c.json_values(texts=False)
        if values is not None:
            (rid, text, source, line, parent, rationale, key, _, _, _, _, _, variables,
             variables_fret, ticks, warnings, causal) = values
            if (type(line) is int and type(causal) is bool
                    and (ticks is None or type(ticks) is int)
                    and type(variables) is list and type(variables_fret) is list
                    and type(warnings) is list):
                try:
                    forms = c.json_forms(enc, seps)
                    if forms is None:
                        f0, f1, f2, f3, f4 = c.printed()
                        forms = (enc(f0) + s0 + enc(f1) + s1 + enc(f2) + s2 + enc(f3) + s3
                                 + enc(f4))
                    return "".join((
                        h_id, enc(rid), h_text, enc(text), h_source, enc(source),
                        h_line, int.__repr__(line),
                        h_parent, "null" if parent is None else enc(parent),
                        h_rationale, "null" if rationale is None else enc(rationale),
                        h_key, enc(key), h_forms, forms,
                        h_vars, "[" + li + lsep.join(map(enc, variables)) + inner + "]"
                        if variables else "[]",
                        h_vars_fret, "[" + li + lsep.join(map(enc, variables_fret)) + inner
                        + "]" if variables_fret else "[]",
                        h_ticks, "null" if ticks is None else int.__repr__(ticks),
                        h_warnings, "[" + li + lsep.join(map(enc, warnings)) + inner + "]"
                        if warnings else "[]",
                        h_causal, scalars[causal], close))
                except TypeError:  # a value that is not a string where one is written
                    pass
        obj = c.to_json()
        try:
            go(obj, "\n  ")
            return "".join(parts)
        except (_NotPlain, RecursionError):
            import json  # lazy: only for values outside the plain shapes
            return json.dumps(obj, indent=2).replace("\n", "\n  ")
        finally:
            parts.clear()

    return item


def _emit_ltl(compiled) -> None:
    """``--emit ltl``'s text: per requirement its id, place, text, key, ft, ft_inf, pt and
    warnings (or its error)."""
    for c in compiled:
        # one line each: a newline in an id or a text (a FRET JSON string) is escaped
        click.echo(visible(f"{c.id}  ({c.location()})"))
        click.echo(visible(f"  text    {c.text}"))
        if c.formalization is not None:
            f = c.formalization
            b = c.probability
            if b is not None:  # FRET's keys: the five-part one, and the LTL's
                click.echo(f"  key     {c.key_pctl}")
                click.echo(f"  key_ltl {f.key}")
            else:
                click.echo(f"  key     {f.key}")
            click.echo(f"  ft      {c.smv_text['ft']}")
            click.echo(f"  ft_inf  {c.smv_text['ft_inf']}")
            click.echo(f"  pt      {c.smv_text['pt']}")
            if b is not None:
                # FRET's PCTL: the bound at each trigger; ft/ft_inf/pt judge one run
                pctl = c.pctl()
                click.echo(f"  pctl    {pctl}" if pctl is not None
                           else _shown(f"  pctl    none: {c.pctl_unsupported()}"))
                click.echo(f"  note    probability {b.op} {b.text} applies to each trigger: "
                           "one log gives its triggers' outcomes; fleets and 'fretc "
                           "estimate' judge the bound over triggers (docs/guide/"
                           "statistics.md)")
            for w in f.warnings:
                click.echo(f"  warning {w}")
        elif c.freeform:
            click.echo("  free-form: kept, not formalized")
        else:
            click.echo(_shown("  error   " + getattr(c.error, "message", str(c.error))))
        click.echo("")


def _check_output(outputs: dict, output: str | None, suffix: str) -> None:
    """``-o`` is a file for one output and a directory for several: a path ending in
    ``suffix`` for several outputs is an error (it would become a directory named so)."""
    from pathlib import Path  # lazy: --emit ltl does not need it (start-up time)
    if output is not None and len(outputs) > 1 and Path(output).suffix == suffix:
        click.echo(f"error: -o {output}: {len(outputs)} modules are written (one per input "
                   f"file: {', '.join(sorted(outputs))}); give a directory (no {suffix} "
                   "suffix) or one input file", err=True)
        sys.exit(2)


def _inputs(files: Sequence[str], psl_map: str | None) -> tuple[list, list]:
    """The inputs compile's outputs are compared with: ``(files, folders)``, the requirement
    files (and ``--psl-map``) and the folders of requirements read
    (:func:`fretc.cli.options.requirement_inputs`)."""
    from fretc.cli.options import requirement_inputs

    req_files, req_folders = requirement_inputs(files)
    return req_files + [("--psl-map", psl_map)], req_folders


def _write_outputs(outputs: dict, output: str | None, suffix: str,
                   inputs: tuple[list, list] = ([], [])) -> None:
    """``outputs`` maps a file stem to text. One output and ``-o FILE``: write the file;
    ``-o DIR``: one file per stem; no ``-o``: print them. No file written is one of
    ``inputs`` (:func:`_inputs`), nor ``-o DIR`` a folder of requirements read: refused
    before any is written (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    if output is None:
        for text in outputs.values():
            click.echo(text, nl=False)
        return
    from pathlib import Path  # lazy: --emit ltl does not need it (start-up time)

    from fretc.common.outputs import output_folder, write_file

    from fretc.cli.options import refuse_outputs_over_inputs
    out = Path(output)
    one = len(outputs) == 1 and not out.is_dir() and not output.endswith(("/", "\\"))
    refuse_outputs_over_inputs([("-o", out)] if one else
                               [("-o", out / f"{stem}{suffix}") for stem in outputs],
                               inputs[0], [] if one else [("-o", out)], inputs[1])
    if one:
        # one module: -o is the file
        output_folder(out.parent)
        write_file(out, next(iter(outputs.values())))
        click.echo(f"wrote {out}", err=True)
        return
    output_folder(out)
    for stem, text in outputs.items():
        path = out / f"{stem}{suffix}"
        write_file(path, text)
        click.echo(f"wrote {path}", err=True)
