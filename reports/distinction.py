"""How ``fretc distinguish`` shows its answer (:mod:`fretc.monitors.distinguish`): the words
``not equivalent`` / ``equivalent`` / ``unknown`` first, then each wording with its verdict on
the distinguishing trace, and the trace drawn as ``fretc explain`` draws its traces (a row
per variable, ``T``/``.`` per tick for a boolean, the values for a number), then how it was
found or proved. Same input, same text."""

from __future__ import annotations

__all__ = ["distinction_text"]


def _cell(value) -> str:
    if isinstance(value, bool):
        return "T" if value else "."
    return f"{value:g}" if isinstance(value, float) else str(value)


def _rows(trace: dict[str, list]) -> list[str]:
    """The trace's rows: booleans one character a tick, numbers in aligned columns."""
    n = len(next(iter(trace.values())))
    numeric = any(not isinstance(v, bool) for vals in trace.values() for v in vals)
    width = max([len(_cell(v)) for vals in trace.values() for v in vals] + [len(str(n - 1))])
    sep = " " if numeric else ""
    w = max(len(v) for v in list(trace) + ["tick"])
    if numeric:
        head = sep.join(f"{i:>{width}}" for i in range(n))
        body = [f"    {v:<{w}}  " + sep.join(f"{_cell(x):>{width}}" for x in vals)
                for v, vals in trace.items()]
    else:
        head = "".join(str(i % 10) for i in range(n))
        body = [f"    {v:<{w}}  " + "".join(_cell(x) for x in vals) for v, vals in trace.items()]
    return [f"    {'tick':<{w}}  {head}"] + body


def distinction_text(d, label_a: str, text_a: str, label_b: str, text_b: str) -> str:
    """The answer ``d`` (:class:`fretc.monitors.distinguish.Distinction`) for the terminal;
    ``label_*`` name the two wordings (an id, or ``A``/``B``), ``text_*`` are their texts."""
    wa = max(len(label_a), len(label_b))
    if d.equivalent is False:
        n = len(next(iter(d.trace.values())))
        out = [f"not equivalent: {label_a} and {label_b} disagree on "
               + ("this shortest trace" if d.shortest else "this trace")
               + f" of {n} tick{'s' if n != 1 else ''}",
               f"  {label_a:<{wa}}  {d.verdicts[0]:<9}  {text_a}",
               f"  {label_b:<{wa}}  {d.verdicts[1]:<9}  {text_b}", ""]
        out += _rows(d.trace)
        out += ["", f"  found by: {d.proof}"]
    elif d.equivalent:
        out = [f"equivalent: {label_a} and {label_b} give the same verdict on every finite "
               "trace", f"  {label_a:<{wa}}  {text_a}", f"  {label_b:<{wa}}  {text_b}", "",
               f"  proof: {d.proof}"]
    else:
        out = [f"unknown: whether {label_a} and {label_b} are equivalent was not decided",
               f"  {label_a:<{wa}}  {text_a}", f"  {label_b:<{wa}}  {text_b}", "",
               f"  why: {d.why}"]
    out += [f"  note: {n}" for n in d.notes]
    return "\n".join(out) + "\n"
