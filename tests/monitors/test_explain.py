"""``fretc explain``: every one of FRET's 288 template keys has a reading and a diagram, and
each diagram says what the requirement means. Checked independently of the interval
semantics the diagram is computed by: scope intervals and triggers against the oracle of
tests/differential.py, and the drawn windows against FRET's ft formula (the reference
evaluator): the response given exactly on the required window satisfies the requirement,
never given violates it, given on the forbidden window violates it."""

from __future__ import annotations

import sys
from pathlib import Path

from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fretc.compiler.build import compile_entries  # noqa: E402
from fretc.compiler.evaluate import ft_at  # noqa: E402
from fretc.compiler.template_table import ALL_KEYS  # noqa: E402
from fretc.cli import main  # noqa: E402
from fretc.fretish.files import load_requirements  # noqa: E402
from fretc.monitors.explain import explain  # noqa: E402

SCOPE = {"null": "", "in": "in m mode ", "notin": "when not in m mode ",
         "onlyIn": "only in m mode ", "after": "after m mode ", "before": "before m mode ",
         "onlyAfter": "only after m mode ", "onlyBefore": "only before m mode "}
COND = {"null": "", "regular": "upon c ", "holding": "whenever c "}
TIMING = {"null": "", "immediately": "immediately ", "next": "at the next timepoint ",
          "finally": "finally ", "eventually": "eventually ", "always": "always ",
          "never": "never ", "within": "within 3 ticks ", "for": "for 3 ticks ",
          "after": "after 3 ticks ", "until": "until s ", "before": "before s "}
KEYS = sorted({(s, c, t) for s, c, t, _n in ALL_KEYS})


def _compiled(tmp_path: Path):
    text = "".join(f"K{i}: {SCOPE[s]}{COND[c]}the sw shall {TIMING[t]}satisfy r\n"
                   for i, (s, c, t) in enumerate(KEYS))
    (tmp_path / "keys.fret").write_text(text)
    return compile_entries(load_requirements([tmp_path / "keys.fret"]))


def _trace(d, r_ticks: set[int], trigger: int | None):
    """The diagram's example trace with the condition a single pulse at the first trigger
    (one obligation to look at) and the response true exactly at ``r_ticks``."""
    rows = []
    for i in range(d.n):
        rows.append({"m": d.signals.get("scope mode", [False] * d.n)[i],
                     "c": i == trigger,
                     "s": d.signals.get("stop condition", [False] * d.n)[i],
                     "r": i in r_ticks})
    return rows


def test_every_template_key_has_a_reading_and_a_diagram_that_means_it(tmp_path):
    from differential import _intervals

    compiled = _compiled(tmp_path)
    assert len(compiled) == len(KEYS) == 288
    checked = 0
    for c, (scope, cond, timing) in zip(compiled, KEYS):
        assert c.error is None, (c.id, c.error)
        x = explain(c)
        d = x.diagram
        assert x.reading and x.key == f"{scope},{cond},{timing},satisfaction"
        mode = d.signals.get("scope mode")
        want = _intervals(scope, mode, d.n, False)
        assert [tuple(iv) for iv in want] == [tuple(iv) for iv in d.scope], (c.id, want, d.scope)
        if not d.triggers:
            continue
        t = d.triggers[0]
        trig = None if cond == "null" else t  # a null condition triggers at the interval start
        if d.required is not None:
            lo, hi = d.required
            ok = _trace(d, set(range(lo, hi + 1)), trig)
            assert ft_at(c.formalization.ft, ok), (c.id, "required window given", d.required)
            assert not ft_at(c.formalization.ft, _trace(d, set(), trig)), (c.id, "never given")
            checked += 1
        if d.forbidden is not None:
            lo, hi = d.forbidden
            bad = _trace(d, set(range(lo, hi + 1)), trig)
            assert not ft_at(c.formalization.ft, bad), (c.id, "forbidden window given")
            checked += 1
    assert checked >= 80


def test_the_command_prints_the_reading_and_writes_svgs(tmp_path):
    root = Path(__file__).resolve().parents[2]
    res = CliRunner().invoke(main, ["explain", str(root / "requirements" / "safe_ros.fret"),
                                    "R2", "-o", str(tmp_path)])
    assert res.exit_code == 0, res.output
    assert "each time too_close becomes true" in res.output
    assert "within 1 second (10 ticks, 1 s)" in res.output
    assert "response required  ..###########" in res.output
    assert (tmp_path / "R2.svg").read_text().startswith("<svg")
    res = CliRunner().invoke(main, ["explain", str(root / "requirements" / "safe_ros.fret"),
                                    "R9"])
    assert res.exit_code == 2 and "no requirement 'R9'" in res.output


def test_the_shortest_traces_are_verdicts_of_fret_and_shortest(tmp_path):
    """The satisfying and violating traces get those verdicts from FRET's ft formula, and no
    shorter trace gets them (brute force over every trace up to the found length - 1)."""
    import itertools
    import random

    from fretc.monitors.explain import shortest_traces

    compiled = _compiled(tmp_path)
    for c in random.Random(3).sample(compiled, 40):
        sat, viol, _note = shortest_traces(c)
        names = list(c.formalization.variables)
        for trace, want in ((sat, True), (viol, False)):
            if trace is None:
                continue
            n = len(trace[names[0]])
            rows = [{v: trace[v][i] for v in names} for i in range(n)]
            assert ft_at(c.formalization.ft, rows) is want, (c.id, c.text, trace)
            for length in range(1, min(n, 4)):
                for bits in itertools.product((False, True), repeat=length * len(names)):
                    rows = [dict(zip(names, bits[i * len(names):(i + 1) * len(names)]))
                            for i in range(length)]
                    assert ft_at(c.formalization.ft, rows) is not want, (c.id, length, rows)


def test_a_million_tick_window_is_drawn_short_and_says_so(tmp_path):
    """A 10^6-tick window was drawn tick by tick: a 138 MB SVG and a megabyte per terminal
    row. Now drawn MAX_DRAWN_TICKS long, marked not to scale, in a small file."""
    from fretc.monitors.explain import MAX_DRAWN_TICKS

    (tmp_path / "r.fret").write_text("R1: upon p the robot shall within 1000000 ticks "
                                     "satisfy q\nR2: upon p the robot shall within 5 ticks "
                                     "satisfy q\n")
    res = CliRunner().invoke(main, ["explain", str(tmp_path / "r.fret"), "-o",
                                    str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    assert "not to scale: the duration of 1000000 ticks is drawn as " \
        f"{MAX_DRAWN_TICKS}" in res.output
    rows = [line for line in res.output.splitlines() if "response required" in line]
    assert rows and max(map(len, rows)) < 200
    big = (tmp_path / "o" / "R1.svg").read_text()
    assert len(big) < 50_000 and "not to scale" in big
    assert "not to scale" not in (tmp_path / "o" / "R2.svg").read_text()


def test_ids_that_map_to_one_file_name_get_their_own_svgs(tmp_path):
    import json

    reqs = [{"reqid": i, "fulltext": "upon p the robot shall within 2 ticks satisfy q"}
            for i in ("a/b", "a_b", "a b")]
    (tmp_path / "r.json").write_text(json.dumps(reqs))
    res = CliRunner().invoke(main, ["explain", str(tmp_path / "r.json"), "-o",
                                    str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    titles = sorted(p.read_text().split("<title>")[1].split(":")[0]
                    for p in (tmp_path / "o").glob("*.svg"))
    assert titles == ["a b", "a/b", "a_b"]
