"""FRET's stream variables (an Internal variable whose Lustre definition reads itself through
``pre``) read as equations (fretish/fret_definitions.py, fretish/fret_streams.py) and
computed tick by tick (compiler/stream_code.py), against a plain Python loop of each Lustre
definition written out here: ``a -> b`` is ``a`` at the first tick, ``pre e`` is ``e`` at
the previous tick (FRET's ``preBool(false, e)`` / ``preReal(0, e)`` at the first)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_definitions import definitions
from fretc.fretish.fret_streams import stream_system
from fretc.fretish.fret_variables import FretVariable

PSI = "Psi -> if (hdg and not pre hdg) then Psi else pre psiAtZero"
ROLL = ("roll_angle -> if (autopilot_engaged and not hdg and not pre (autopilot_engaged and "
        "not hdg)) then roll_angle else pre rollAtZero")


def _vars(internal: dict[str, tuple[str, str]], inputs: dict[str, str]) -> tuple:
    return tuple([FretVariable("c", n, "Input", t) for n, t in inputs.items()]
                 + [FretVariable("c", n, "Internal", t, a) for n, (t, a) in internal.items()])


LMCPS = _vars({"psiAtZero": ("double", PSI), "rollAtZero": ("double", ROLL)},
              {"Psi": "double", "hdg": "boolean", "autopilot_engaged": "boolean",
               "roll_angle": "double"})
MUTUAL = _vars({"a": ("boolean", "false -> pre b"), "b": ("boolean", "x and not a"),
                "big": ("boolean", "a or y > 2.0")}, {"x": "boolean", "y": "double"})
NESTED = _vars({"d": ("", "y -> pre (pre d) + 1.0"),
                "seen": ("boolean", "x -> (x or pre seen)"),
                "half": ("", "if seen then d / 2.0 else d mod 2.0")},
               {"x": "boolean", "y": "double"})


def ref_lmcps(v: dict) -> dict:
    psi, roll = [], []
    for t in range(len(v["Psi"])):
        eng = v["autopilot_engaged"][t] and not v["hdg"][t]
        if t == 0:
            psi.append(v["Psi"][0])
            roll.append(v["roll_angle"][0])
            continue
        psi.append(v["Psi"][t] if v["hdg"][t] and not v["hdg"][t - 1] else psi[-1])
        was = v["autopilot_engaged"][t - 1] and not v["hdg"][t - 1]
        roll.append(v["roll_angle"][t] if eng and not was else roll[-1])
    return {"psiAtZero": psi, "rollAtZero": roll}


def ref_mutual(v: dict) -> dict:
    a, b, big = [], [], []
    for t in range(len(v["x"])):
        a.append(False if t == 0 else b[t - 1])
        b.append(v["x"][t] and not a[t])
        big.append(a[t] or v["y"][t] > 2.0)
    return {"a": a, "b": b, "big": big}


def ref_nested(v: dict) -> dict:
    import math

    d, seen, half = [], [], []
    for t in range(len(v["x"])):
        pp = d[t - 2] if t >= 2 else 0.0  # pre (pre d): 0 where FRET's pre has no value
        d.append(v["y"][t] if t == 0 else pp + 1.0)
        seen.append(v["x"][t] if t == 0 else (v["x"][t] or seen[t - 1]))
        half.append(d[t] / 2.0 if seen[t] else math.fmod(d[t], 2.0))
    return {"d": d, "seen": seen, "half": half}


def test_the_streams_and_their_order():
    assert list(definitions(LMCPS).streams) == ["psiAtZero", "rollAtZero"]
    assert list(definitions(MUTUAL).streams) == ["a", "b", "big"]
    # (the audit's and the monitors' reading: every stream tick by tick; the analyses'
    # read seen, a latch monotone in its previous value, as a since: fretish.fret_since)
    assert list(definitions(NESTED, since=False).streams) == ["d", "seen", "half"]
    assert list(definitions(NESTED).streams) == ["d", "half"]
    assert definitions(NESTED).pasts == {"seen"}
    s = stream_system(MUTUAL, ["big"])
    assert s is not None and s.names == ("a", "b", "big") and s.inputs == ("x", "y")
    assert s.booleans == (True, True, True)
    assert stream_system(LMCPS, ["Psi"]) is None
    assert stream_system(LMCPS, ["psiAtZero"], keep={"psiAtZero"}) is None


def test_what_stays_free():
    """A cycle outside ``pre`` (Lustre's causality), a glossary function, and what reads
    them are no streams: free, with the reason the analyses give."""
    loop = _vars({"p": ("boolean", "x -> pre p and q"), "q": ("boolean", "p"),
                  "f": ("", "y -> g(y) + pre f"), "r": ("boolean", "p or x")},
                 {"x": "boolean", "y": "double"})
    defs = definitions(loop)
    assert defs.streams == {}
    assert set(defs.free) == {"p", "q", "f", "r"}


def _inputs(data, system) -> dict:
    n = data.draw(st.integers(1, 12))
    out = {}
    for name, boolean in zip(system.inputs, system.input_booleans):
        out[name] = data.draw(st.lists(st.booleans() if boolean else st.sampled_from(
            [-2.0, 0.0, 1.5, 3.0, 7.0]), min_size=n, max_size=n))
    return out


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([(LMCPS, ref_lmcps), (MUTUAL, ref_mutual), (NESTED, ref_nested)]),
       st.data())
def test_columns_equal_the_lustre_loop(case, data):
    variables, ref = case
    system = stream_system(variables, definitions(variables).streams)
    assert system is not None
    values = _inputs(data, system)
    n = len(next(iter(values.values())))
    got = stream_columns(system, {k: np.array(v, dtype=np.bool_ if isinstance(v[0], bool)
                                              else np.float64) for k, v in values.items()}, n)
    want = ref(values)
    for name in system.names:
        assert got[name].tolist() == want[name], name


def _three(system, values: dict, unknown: dict, n: int) -> dict:
    cols = {k: np.array(v, dtype=np.bool_ if isinstance(v[0], bool) else np.float64)
            for k, v in values.items()}
    return stream_columns(system, cols, n, {k: np.array(v, dtype=np.bool_)
                                            for k, v in unknown.items()})


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([(LMCPS, ref_lmcps), (MUTUAL, ref_mutual), (NESTED, ref_nested)]),
       st.data())
def test_a_known_value_is_the_same_whatever_the_unknown_inputs_were(case, data):
    """Kleene's reading of the unknown inputs (stream_columns with ``unknown``): where a
    value is known, every way of filling the unknown inputs gives it (a few drawn here,
    through the reference loop)."""
    variables, ref = case
    system = stream_system(variables, definitions(variables).streams)
    assert system is not None
    values = _inputs(data, system)
    n = len(next(iter(values.values())))
    unknown = {k: data.draw(st.lists(st.booleans(), min_size=n, max_size=n))
               for k in values}
    got = _three(system, values, unknown, n)
    for _ in range(4):
        filled = {k: [data.draw(st.booleans() if isinstance(x, bool) else st.sampled_from(
            [-2.0, 0.0, 1.5, 7.0])) if unknown[k][t] else x for t, x in enumerate(v)]
            for k, v in values.items()}
        other = ref(filled)
        for name in system.names:
            for t in range(n):
                if not got[f"{name}?"][t]:
                    assert got[name][t] == other[name][t], (name, t)


def test_a_reset_makes_it_known_again():
    system = stream_system(LMCPS, ["psiAtZero"])
    values = {"Psi": [0.0, 3.0, 7.0, 9.0, 9.0], "hdg": [False, True, True, False, True]}
    got = _three(system, values, {"Psi": [False, True, False, False, False]}, 5)
    assert got["psiAtZero?"].tolist() == [False, True, True, True, False]
    assert got["psiAtZero"][4] == 9.0
    nan = _three(system, dict(values, Psi=[0.0, float("nan"), 7.0, 9.0, 9.0]), {}, 5)
    assert nan["psiAtZero?"].tolist() == [False, True, True, True, False]


BARE = _vars({"p": ("boolean", "pre q"), "q": ("boolean", "x and not p")}, {"x": "boolean"})


@settings(max_examples=40, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=12))
def test_a_bare_pre(xs):
    """``p`` is ``pre q`` alone (no ``->``: FRET's false at the first tick): its value at a
    tick is the slot's before the tick's update."""
    system = stream_system(BARE, ["p"])
    assert system is not None and system.names == ("p", "q")
    p, q = [], []
    for t, x in enumerate(xs):
        p.append(False if t == 0 else q[t - 1])
        q.append(x and not p[t])
    got = stream_columns(system, {"x": np.array(xs, dtype=np.bool_)}, len(xs))
    assert got["p"].tolist() == p and got["q"].tolist() == q
    three = stream_columns(system, {"x": np.array(xs, dtype=np.bool_)}, len(xs), {})
    assert three["p"].tolist() == p and not three["p?"].any()


def test_after_a_gap_tick_nothing_held_is_known():
    """A tick standing for an unknown number of ticks (a gap of the tick topic): a reset
    may have happened in them, so psiAtZero is unknown until the next known reset."""
    system = stream_system(LMCPS, ["psiAtZero"])
    values = {"Psi": [0.0, 3.0, 7.0, 9.0, 9.0, 4.0],
              "hdg": [False, True, True, True, False, True]}
    cols = {k: np.array(v, dtype=np.bool_ if isinstance(v[0], bool) else np.float64)
            for k, v in values.items()}
    got = stream_columns(system, cols, 6, {}, gaps=[2])
    assert got["psiAtZero?"].tolist() == [False, False, True, True, True, False]
    assert not stream_columns(system, cols, 6, {})["psiAtZero?"].any()


@settings(max_examples=40, deadline=None)
@given(st.sampled_from([(LMCPS, ref_lmcps), (MUTUAL, ref_mutual), (NESTED, ref_nested),
                        (BARE, None)]), st.data())
def test_the_monitors_factory_steps_as_the_columns(case, data):
    """The generated monitors' per-step code (python_factory: state kept between steps)
    gives the audit's columns, tick by tick."""
    from fretc.compiler.stream_code import python_factory

    variables, _ref = case
    system = stream_system(variables, definitions(variables).streams)
    assert system is not None
    values = _inputs(data, system)
    n = len(next(iter(values.values())))
    space: dict = {"_div": lambda a, b: a / b if b else float("nan"),
                   "_mod": __import__("math").fmod, "_pow": pow}
    exec(python_factory(system, "factory"), space)
    init, tick = space["factory"](*system.inputs, *system.names)
    state, got = init(), {name: [] for name in system.names}
    for t in range(n):
        state, now = tick(state, {k: v[t] for k, v in values.items()})
        for name in system.names:
            got[name].append(now[name])
    want = stream_columns(system, {k: np.array(v, dtype=np.bool_ if isinstance(v[0], bool)
                                               else np.float64) for k, v in values.items()}, n)
    for name in system.names:
        assert np.array(got[name], dtype=want[name].dtype).tolist() == want[name].tolist()
