"""The report's parts on their own: the timeline layout (1-2-5 steps, the broken detail axis),
a verdict as a matrix cell and a values table, the requirement's thresholds and source
positions. Property-based where the rule is general (hypothesis)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from fretc.fretish.parser import parse
from fretc.reports.trace import split_source, thresholds
from fretc.reports.verdicts import cell_label, values_table, verdict_for
from fretc.reports.timeline_layout import (PLOT_X1, Threshold, nice_step_ns, plan_timeline,
    step_decimals)


@settings(max_examples=200, deadline=None)
@given(span=st.integers(1, 10**13), px=st.floats(10, 2000), min_px=st.floats(10, 120))
def test_nice_step_is_the_smallest_1_2_5_step_that_keeps_labels_apart(span, px, min_px):
    step = nice_step_ns(span, px, min_px)
    mantissa = step // 10 ** (len(str(step)) - 1)
    assert mantissa in (1, 2, 5) and str(step).rstrip("0") == str(mantissa)
    per_px = span / px
    if step < 10**12:
        assert step / per_px >= min_px
    smaller = [m * 10**e for e in range(3, 13) for m in (1, 2, 5) if m * 10**e < step]
    assert all(s / per_px < min_px for s in smaller)
    assert 0 <= step_decimals(step) <= 6


def _verdict(ticks: list[int], period: int = 100_000_000, start: int = 10**18) -> dict:
    rows = [{"tick": k, "time_ns": start + k * period, "time_s": k * period / 1e9,
             "value": k % 2 == 0} for k in ticks]
    last = ticks[-1]
    return {"requirement": "R", "log": "x.mcap", "values": {"a": rows}, "sources": {},
            "first_violation": {"tick": last, "log_time_ns": start + last * period,
                                "log_time_s": last * period / 1e9,
                                "tick_time_s": last * period / 1e9}}


@st.composite
def _windows(draw) -> list[int]:
    """Sampled ticks as the audit gives them: at most three runs of consecutive ticks
    (around the trigger, the violation, the LTL3 verdict)."""
    ticks: set[int] = set()
    for _ in range(draw(st.integers(1, 3))):
        lo = draw(st.integers(0, 400))
        ticks.update(range(lo, lo + draw(st.integers(1, 12))))
    return sorted(ticks)


@settings(max_examples=100, deadline=None)
@given(_windows())
def test_detail_axis_is_monotonic_and_inside_the_plot(ticks):
    start = 10**18
    v = _verdict(ticks, start=start)
    lay = plan_timeline(v, {"start_time_ns": start, "end_time_ns": start + 500 * 10**8},
                        10**8, ())
    # one window per run of consecutive ticks, in order, not overlapping
    runs = 1 + sum(1 for a, b in zip(ticks, ticks[1:]) if b != a + 1)
    assert len(lay.segs) == runs
    assert all(a.q <= b.p for a, b in zip(lay.segs, lay.segs[1:]))
    xs = [lay.axis.x(start + k * 10**7)[0] for k in range(0, 4100, 7)]
    assert xs == sorted(xs)
    assert all(lay.x0 <= x <= PLOT_X1 + 1e-6 for x in xs)


def test_cell_label_and_values_table_of_a_violation():
    v = _verdict([3, 4, 5, 9, 10])
    v["verdict"] = "violated"
    v["first_violation"]["trigger"] = {"tick": 4, "time_ns": 0, "time_s": 0.4}
    v["first_violation"]["window"] = {"start_tick": 4, "end_tick": 9}
    assert cell_label(v) == ("violated", "violated @ 1.000 s")
    assert cell_label(None) == ("none", "not audited")
    table = values_table(v, 10**18)
    assert [r["tick"] for r in table["rows"]] == [3, 4, 5, 9, 10]
    assert [r["gap"] for r in table["rows"]] == [False, False, False, True, False]
    assert [r["window"] for r in table["rows"]] == [False, True, True, True, False]
    assert [r["marks"] for r in table["rows"]] == ["", "trigger", "", "", "violation"]
    assert [c["text"] for r in table["rows"] for c in r["cells"]] == ["F", "T", "F", "F", "T"]


def test_verdict_for_matches_by_id_then_source():
    la = {"verdicts": [{"requirement": "B", "source": "b:1"}, {"requirement": "A",
                                                              "source": "a:1"},
                       {"requirement": "A", "source": "a:2"}]}
    assert verdict_for(la, 0, {"id": "B"})["source"] == "b:1"
    assert verdict_for(la, 0, {"id": "A", "source": "a:2"})["source"] == "a:2"
    assert verdict_for(la, 0, {"id": "A"}) is None          # ambiguous: not guessed
    assert verdict_for(la, 0, {"id": "C"}) is None


@given(st.text(alphabet="ab/:.", max_size=12), st.integers(0, 10**6))
def test_split_source_takes_the_last_line_number(file, line):
    assert split_source(f"{file}:{line}") == (file, line)


def test_thresholds_turn_constant_first_comparisons_round():
    req = parse("when 0.5 > d the robot shall always satisfy -1 <= v & v < 2 & d > 0.5")
    assert thresholds(req) == [Threshold("d", "<", 0.5), Threshold("v", ">=", -1.0),
                                         Threshold("v", "<", 2.0), Threshold("d", ">", 0.5)]


HOSTILE_MD = ["![x](http://evil.example/i.png)", "[click](http://evil.example)",
              "<img src=http://evil.example/i.png>", "http://evil.example/a",
              "www.evil.example", "<http://evil.example>", "# heading", "*em* _em_ `c`",
              "a | b", "&lt;script&gt;", "R1\nR2", "\u202eevil"]


@pytest.mark.parametrize("text", HOSTILE_MD)
def test_markdown_text_renders_as_itself(text):
    """Ids, rationales and every other text in report.md render as plain text: no link,
    image, tag, heading or emphasis (CommonMark with GFM tables and linkify)."""
    from markdown_it import MarkdownIt

    from fretc.reports.render import _md

    md = MarkdownIt("commonmark").enable("table")
    try:
        md = md.enable("linkify")  # needs linkify-it-py; GFM's bare-URL autolinks
    except Exception:
        pass
    html = md.render(f"| id |\n|---|\n| {_md(text)} |\n\n### {_md(text)}\n")
    for bad in ("<img", "<a ", "<em>", "<strong>", "<code>", "<h1", "<script"):
        assert bad not in html, (text, html)
    assert html.count("<td>") == 1 and html.count("<h3>") == 1
