"""FRET's semantics diagram (:mod:`fretc.reports.semantics_diagram`): every scope x condition
x timing of FRET's vectors gets a diagram whose drawn scope intervals, triggers and response
windows are those of FRET's semantics, held against the audit's own scope intervals,
trigger points and obligation checker (a window drawn one tick too short or too long fails)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from fretc.fretish import parse
from fretc.monitors.interval import IntervalStream, scope_intervals, trigger_ticks
from fretc.reports.semantics_diagram import CELL, LEFT, MAX_DRAWN, layout, svg
from tests._shared import jsonl, params

NS = {"s": "http://www.w3.org/2000/svg"}


def _sentences_by_key() -> dict[str, str]:
    """One formalizable sentence of FRET's vectors per template key."""
    out: dict[str, str] = {}
    rows = (jsonl("fretish/fret_vectors.jsonl") + jsonl("fretish/fret_vectors_functions.jsonl"))
    texts = [r["text"] for r in rows if r.get("key") and not r.get("parse_error")
             and not r.get("freeform")]
    texts += [c["sentence"] for t in jsonl("fretish/fret_trace_verdicts.jsonl")
              for c in t["cases"]]
    for text in texts:
        try:
            req = parse(text)
            layout(req)
        except Exception:  # noqa: BLE001 - a sentence fretc rejects is not drawn here
            continue
        out.setdefault(req.key, text)
    return out


def _cases():
    for key, text in sorted(_sentences_by_key().items()):
        yield pytest.param(text, id=key)


def _drawn(root, cls: str) -> list[tuple[int, int]]:
    return [(int(r.get("data-start")), int(r.get("data-end")))
            for r in root.iter("{http://www.w3.org/2000/svg}rect") if r.get("class") == cls]


def test_every_key_of_fret_vectors_is_covered():
    keys = _sentences_by_key()
    if not keys:
        pytest.skip("../shared is absent")
    scopes = {k.split(",")[0] for k in keys}
    conds = {k.split(",")[1] for k in keys}
    timings = {k.split(",")[2] for k in keys}
    assert len(scopes) == 8 and len(conds) == 3 and len(timings) == 12
    assert len(keys) >= 8 * 3 * 11  # every combination the vectors hold (null timing: some)


@pytest.mark.parametrize("text", params(_cases))
def test_diagram_draws_fret_semantics(text):
    req = parse(text)
    lay = layout(req)
    root = ET.fromstring(svg(req, ident="X1"))
    assert root.get("data-key") == req.key
    # the scope intervals: drawn, and those of the audit's interval semantics
    mode = None if lay.mode is None else np.array(lay.mode)
    assert _drawn(root, "scope") == list(lay.intervals)
    assert list(lay.intervals) == scope_intervals(req.scope.kind, mode, lay.n)
    assert lay.intervals, "a diagram shows at least one scope interval"
    # the triggers: drawn, and the audit's trigger points in each interval
    cond = None if lay.condition is None else np.array(lay.condition)
    inside = np.zeros(lay.n, np.bool_)
    for s, e in lay.intervals:
        inside[s:e + 1] = True
    starts = np.array([s for s, _e in lay.intervals], np.int64)
    expected = trigger_ticks(req.condition.kind, cond, inside, starts, False).tolist()
    ticks = [int(p.get("data-tick")) for p in root.iter("{http://www.w3.org/2000/svg}path")
             if p.get("class") == "trigger"]
    assert ticks == list(lay.triggers) == expected
    # windows where they are drawn: x and width in ticks
    for r in root.iter("{http://www.w3.org/2000/svg}rect"):
        if r.get("class") in ("window", "scope"):
            a, b = int(r.get("data-start")), int(r.get("data-end"))
            assert float(r.get("x")) == LEFT + CELL * a
            assert float(r.get("width")) == CELL * (b - a + 1)
    assert _drawn(root, "window") == [(w.start, w.end) for w in lay.windows]
    # the labelled elements
    labels = " ".join("".join(t.itertext()) for t in root.iter("{http://www.w3.org/2000/svg}text"))
    assert "Res: " in labels
    assert ("TC: " in labels) == (req.condition.kind != "null")
    assert ("SC: " in labels) == (req.timing.kind in ("until", "before"))
    assert ("M: " in labels) == (req.scope.kind != "null")
    _check_windows_against_the_audit(req, lay)
    _check_duration(req, lay, root)


def _check_duration(req, lay, root) -> None:
    groups = [g for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("class") == "duration"]
    if lay.k is None:
        assert not groups
        return
    assert groups
    for g in groups:
        t0, t1 = int(g.get("data-from")), int(g.get("data-to"))
        assert t1 - t0 == lay.k == int(g.get("data-ticks"))   # n ticks after the trigger
        d = g.find("s:path", NS).get("d")
        assert d.startswith(f"M{LEFT + CELL * t0 + CELL // 2},")
        assert f"H{LEFT + CELL * t1 + CELL // 2} " in d
        if req.timing.kind == "within" and not lay.negated:
            # the window ends n ticks after the trigger
            assert any(w.trigger == t0 and w.end == t0 + lay.k for w in lay.windows)


def _check_windows_against_the_audit(req, lay) -> None:
    """Each trigger's drawn windows against the audit's interval semantics: the response
    laid on them meets the obligation, with everything else adverse; moved one tick out of
    a window ('some') or broken at a window's end ('every'), it fails."""
    if req.timing.kind == "after" and lay.negated:
        return  # the negated "after" is not a window conjunction (the legend says so)
    S = None if lay.stop is None else np.array(lay.stop)
    for t in sorted({w.trigger for w in lay.windows}):
        mine = [w for w in lay.windows if w.trigger == t]

        def verdict(R, t=t):
            judged = IntervalStream(req, lay.drawn_k or 0, limit=lay.n + 1)
            mode = None if lay.mode is None else np.array(lay.mode)
            C = None if lay.condition is None else np.array(lay.condition)
            judged.feed_signals(mode, R, C, S if S is not None else np.zeros(lay.n, bool),
                                lay.n, np.arange(lay.n))
            return all(v.trigger_tick != t for v in judged.finish()[0].listed)

        base = np.full(lay.n, not mine[0].value)
        for w in mine:
            if w.quantifier == "every":
                base[w.start:w.end + 1] = w.value
            else:
                base[w.end] = w.value
        assert verdict(base), (req.text, t, mine)
        for w in mine:
            if w.quantifier == "every":
                for at in {w.start, w.end}:
                    bad = base.copy()
                    bad[at] = not w.value
                    assert not verdict(bad), (req.text, "every", at)
            else:
                if w.end + 1 < lay.n:
                    moved = base.copy()
                    moved[w.end], moved[w.end + 1] = (not w.value), w.value
                    assert not verdict(moved), (req.text, "past the end", w)
                if w.start >= 1:
                    moved = base.copy()
                    moved[w.end], moved[w.start - 1] = (not w.value), w.value
                    assert not verdict(moved), (req.text, "before the start", w)
                early = base.copy()
                early[w.end], early[w.start] = (not w.value), w.value
                assert verdict(early), (req.text, "at the start", w)


def test_a_long_duration_is_drawn_short_and_says_so():
    req = parse("upon p the sw shall within 500 ticks satisfy q")
    lay = layout(req)
    assert lay.k == 500 and lay.drawn_k == MAX_DRAWN and lay.n < 40
    text = svg(req)
    assert "n = 500 ticks (not to scale)" in text
    g = next(x for x in ET.fromstring(text).iter("{http://www.w3.org/2000/svg}g")
             if x.get("class") == "duration")
    assert g.get("data-ticks") == "500"


def test_duration_in_ticks_as_compiled_and_deterministic():
    req = parse("in flight mode upon too_close the robot shall for 2 seconds satisfy stopped")
    a, b = svg(req, ticks=4, ident="R"), svg(req, ticks=4, ident="R")
    assert a == b
    assert "n = 4 ticks" in a and 'data-ticks="4"' in a
    assert layout(req, 4).windows[0].end - layout(req, 4).windows[0].start == 4


def test_hostile_text_stays_well_formed():
    req = parse('upon "a<b&c" the sw shall immediately satisfy q')
    root = ET.fromstring(svg(req, ident="<R&1>"))
    assert "a<b&c" in "".join(root.itertext())


def test_free_form_has_no_diagram():
    with pytest.raises(ValueError, match="free-form"):
        layout(parse('"the robot is nice"'))


def test_explain_writes_the_semantics_diagram(tmp_path):
    """``fretc explain FILE R2 --semantics DIR``: R2 (within 1 second at 100 ms a tick) gets
    a window of 10 ticks after its trigger; an unknown id exits 2 and writes nothing."""
    from pathlib import Path

    from click.testing import CliRunner

    from fretc.cli import main

    reqs = Path(__file__).resolve().parents[2] / "requirements" / "safe_ros.fret"
    out = tmp_path / "sem"
    res = CliRunner().invoke(main, ["explain", str(reqs), "R2", "--semantics", str(out)])
    assert res.exit_code == 0, res.output
    root = ET.fromstring((out / "R2.svg").read_text(encoding="utf-8"))
    (w,) = [r for r in root.iter("{http://www.w3.org/2000/svg}rect")
            if r.get("class") == "window"]
    assert int(w.get("data-end")) - int(w.get("data-trigger")) == 10
    assert w.get("data-quantifier") == "some"
    bad = CliRunner().invoke(main, ["explain", str(reqs), "R99", "--semantics",
                                    str(tmp_path / "none")])
    assert bad.exit_code == 2 and not (tmp_path / "none").exists()
