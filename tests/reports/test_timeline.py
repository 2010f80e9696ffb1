"""Pieces of the report: the requirement text with its fields marked, and the SVG timeline of
a violation (gaps, non-finite values, lanes)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from fretc.fretish.parser import parse
from fretc.reports.trace import marked_fields
from fretc.reports.timeline import timeline_svg
from fretc.reports.timeline_layout import Threshold

from _logs import MS

SVG = "{http://www.w3.org/2000/svg}"

def test_marked_fields_join_back_to_the_text():

    for text in ["in docking mode, upon p & q the sw shall within 3 ticks satisfy r",
                 "the sw shall always satisfy x > 0", "when p the sw shall satisfy q",
                 "after boot, whenever p the sw shall immediately satisfy q"]:
        req = parse(text)
        pieces = marked_fields(text, req)
        assert "".join(p for p, _ in pieces) == text
        names = [f for _, f in pieces if f]
        assert "component" in names and "response" in names
        assert names == sorted(names, key=["scope", "condition", "component", "probability",
                                           "timing", "response"].index)


def _verdict(**kw):
    start = 1_000_000_000_000
    P = 100 * MS
    ticks = list(range(0, 6)) + list(range(40, 46))
    vals = [1.0, 0.8, float("nan"), 0.5, "inf", 0.3, 0.2, 0.1, 0.05, -0.01, "-inf", "nan"]
    v = {
        "requirement": "Z1", "log": "z.mcap", "verdict": "violated", "partial": False,
        "first_violation": {
            "tick": 43, "log_time_ns": start + 43 * P, "log_time_s": 4.3,
            "trigger": {"tick": 2, "time_ns": start + 2 * P, "time_s": 0.2},
            "scope_interval": {"start": {"tick": 1, "time_ns": start + P, "time_s": 0.1},
                               "end": {"tick": 45, "time_ns": start + 45 * P, "time_s": 4.5}},
            "window": {"start_tick": 2, "end_tick": 60, "start_time_ns": start + 2 * P,
                       "end_time_ns": start + 60 * P, "start_time_s": 0.2, "end_time_s": 6.0},
            "obligation": "o", "reason": "r"},
        "ltl3": {"status": "violated", "tick": 44, "time_ns": start + 44 * P, "time_s": 4.4},
        "values": {"x": [{"tick": k, "time_ns": start + k * P, "time_s": k / 10,
                          "value": (v if not isinstance(v, float) or v == v else "nan")}
                         for k, v in zip(ticks, vals)],
                   "b": [{"tick": k, "time_ns": start + k * P, "time_s": k / 10,
                          "value": k % 2 == 0} for k in ticks]},
        "sources": {"/x": [{"tick": k, "time_ns": start + k * P, "time_s": k / 10,
                            "message_log_time_ns": (start + k * P - 5 * MS) if k else None}
                           for k in ticks]},
    }
    v.update(kw)
    log = {"log": "z.mcap", "start_time_ns": start, "end_time_ns": start + 45 * P,
           "damage_time_ns": start + 45 * P}
    return v, log


def test_timeline_svg_marks_gaps_and_non_finite_values():
    v, log = _verdict()
    svg = timeline_svg(v, log, period_ns=100 * MS, thresholds=[Threshold("x", ">", 0.0)])
    assert svg == timeline_svg(v, log, period_ns=100 * MS,
                               thresholds=[Threshold("x", ">", 0.0)])   # deterministic
    root = ET.fromstring(svg)
    marks = {}
    for e in root.iter():
        if e.get("data-mark"):
            marks.setdefault(e.get("data-mark"), set()).add(e.get("data-ns") or e.get("data-value"))
    start = log["start_time_ns"]
    assert marks["violation"] == {str(start + 43 * 100 * MS)}
    assert marks["trigger"] == {str(start + 2 * 100 * MS)}
    assert marks["ltl3"] == {str(start + 44 * 100 * MS)}
    assert marks["threshold"] == {"0"} and "damage" in marks
    assert len(marks["detail"]) == 2                          # two windows, one axis break
    assert "3.4 s" in svg and "skipped" in svg                 # the break says what it skips
    assert "NaN" in svg                                        # NaN drawn as a gap, labelled
    assert "response window reaches past the end of the log (tick 60)" in svg
    assert "log damaged at" in svg and "no message yet" in svg
    lanes = {g.get("data-lane"): g.get("data-kind") for g in root.iter(f"{SVG}g")
             if g.get("data-lane")}
    assert lanes == {"x": "num", "b": "bool", "/x": "topic"}
    # a hostile variable name is escaped
    v2, _ = _verdict()
    v2["values"] = {'<a href="x">&': v2["values"]["b"]}
    ET.fromstring(timeline_svg(v2, log))
    with pytest.raises(ValueError):
        timeline_svg(dict(v, first_violation=None), log)


def test_under_the_header_time_base_the_violation_is_drawn_at_its_tick_time():
    """Header stamps 2 s behind the log time: the violation mark sits on the violated tick
    (the detail windows' clock), not on the deciding message's log time."""
    v, log = _verdict()
    P = 100 * MS
    start = log["start_time_ns"]
    v["first_violation"].update(log_time_ns=start + 43 * P + 2_000 * MS,
                                tick_time_ns=start + 43 * P, tick_time_base="header")

    def violation_marks(verdict):
        root = ET.fromstring(timeline_svg(verdict, log, period_ns=P))
        return {e.get("data-ns") for e in root.iter() if e.get("data-mark") == "violation"}

    assert violation_marks(v) == {str(start + 43 * P)}
    # log time base: the tick's time too (one time per event everywhere)
    v["first_violation"]["tick_time_base"] = "log"
    assert violation_marks(v) == {str(start + 43 * P)}


def _marks(v, log, P):
    root = ET.fromstring(timeline_svg(v, log, period_ns=P))
    out = {}
    for e in root.iter():
        if e.get("data-mark"):
            out.setdefault(e.get("data-mark"), set()).add(int(e.get("data-ns")))
    return out, " ".join(e.text or "" for e in root.iter())


def test_markers_keep_the_order_of_their_ticks_and_the_label_gives_the_tick_time():
    """Before, the violation was drawn at 29.775 s (its deciding message) before its
    trigger at 29.800 s, and labelled 6.900 s where the terminal said 6.903 s."""
    from fretc.common.units import format_offset
    v, log = _verdict()
    P = 100 * MS
    start = log["start_time_ns"]
    fv = v["first_violation"]
    # violated at the trigger's own tick, decided by a message held from 25 ms before it
    fv.update(tick=2, tick_time_ns=start + 2 * P, tick_time_s=0.2, tick_time_base="log",
              log_time_ns=start + 2 * P - 25 * MS)
    marks, text = _marks(v, log, P)
    assert marks["violation"] == marks["trigger"] == {start + 2 * P}
    assert min(marks["ltl3"]) >= max(marks["violation"])
    assert f"violation {format_offset(start + 2 * P, start)}" in text


def test_the_footer_states_the_origin_as_what_it_is():
    """Before, the footer said "since the log's first tick" but measured from the log's
    start (its first message)."""
    v, log = _verdict()
    _, text = _marks(v, log, 100 * MS)
    assert "since the log's first tick" not in text
    assert f"since the log's start, its first message (t0 = {log['start_time_ns']} ns" in text


def test_the_caption_names_requirement_run_verdict_and_time():
    """A timeline pasted alone still says what it shows: its first text is the caption,
    with the requirement, the run, the verdict and the violation's time on the log clock
    (the verdict's own, not a constant)."""
    for req, log_name, word, tick in (("Z1", "z.mcap", "violated", 43),
                                      ("R7", "runs/a b.mcap", "violated", 41)):
        v, log = _verdict(requirement=req, log=log_name, verdict=word)
        v["first_violation"]["tick"] = tick
        v["first_violation"]["log_time_ns"] = log["start_time_ns"] + tick * 100 * MS
        root = ET.fromstring(timeline_svg(v, log, period_ns=100 * MS))
        texts = [t for t in root.iter(f"{SVG}text")]
        assert texts[0].get("class") == "caption"
        cap = texts[0].text
        assert cap.startswith(f"{req} {word} on run {log_name}: ")
        assert f"at {tick / 10:.3f} s on the log clock" in cap
        given = timeline_svg(v, log, period_ns=100 * MS, caption="mine <&>")
        assert ET.fromstring(given).find(f"{SVG}text").text == "mine <&>"
