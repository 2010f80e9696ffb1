"""``fretc EXPORT --emit monitor`` (and ``c``, ``c2po``) of a FRET export whose requirement
reads an Internal variable FRET's glossary defines: the monitor computes the variable from
the variables its definition reads, as FRET's own monitors (Ogma's Copilot streams) do, so
its inputs are those variables; each definition used is said once on stderr. One that reads
itself through ``pre`` (a stream with state) is computed by the monitor tick by tick
(tests/compiler/test_monitor_streams.py); R2U2's C2PO reads it as an input signal, with the reason. The
monitor steps as the same requirement with the definition written out in FRETish."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from _monitor_helpers import fret_export
from fretc.cli import main

_VARIABLES = fret_export({}, ("a", "Input", "boolean"), ("o", "Output", "boolean"),
                         ("rise", "Internal", "boolean", "a and not pre a"),
                         ("seen", "Internal", "boolean", "a -> (a or pre seen)"),
                         ("toggle", "Internal", "boolean", "false -> (a xor pre toggle)")
                         )["variables"]


def _monitors(tmp: Path, text: str, emit: str = "monitor") -> tuple[dict, str]:
    """The module ``--emit monitor`` writes for the one-requirement export ``text`` (its
    globals), and what the command printed on stderr."""
    src = tmp / "p.json"
    src.write_text(json.dumps({"requirements": [{"reqid": "R1", "fulltext": text}],
                               "variables": _VARIABLES}), encoding="utf-8")
    out = tmp / ("m.py" if emit == "monitor" else "out")
    got = CliRunner().invoke(main, [str(src), "--emit", emit, "-o", str(out)])
    assert got.exit_code == 0, got.output
    return (runpy.run_path(str(out)) if emit == "monitor" else {"out": out}), got.stderr


def test_the_monitor_reads_the_variables_the_definition_reads(tmp_path):
    mod, err = _monitors(tmp_path, "whenever rise ctrl shall immediately satisfy o")
    assert mod["MONITORS"]["R1"]().VARIABLES == ["a", "o"]
    assert "note: rise: FRET defines it (Internal) as a and not pre a; that definition in " \
           "the monitor" in err
    # one that reads itself (a stream with state) is computed by the monitor too, tick by
    # tick: its inputs are the variables it reads, and the note says so
    mod, err = _monitors(tmp_path, "whenever seen ctrl shall immediately satisfy o")
    assert sorted(mod["MONITORS"]["R1"]().VARIABLES) == ["a", "o"]
    assert "seen: FRET defines it (Internal) as a -> (a or pre seen); that definition is a " \
           "stream with state (it reads itself through pre): computed tick by tick" in err
    # R2U2's C2PO reads one that no past-time formula writes (a toggle: the parity of a's
    # ticks) as an input signal, and says why and what the trace must carry
    _got, err = _monitors(tmp_path, "whenever toggle ctrl shall immediately satisfy o", "c2po")
    assert "toggle: FRET defines it (Internal) as false -> (a xor pre toggle); that " \
           "definition is a stream with state (it reads itself through pre): an input " \
           "signal of the C2PO " \
           "specification: R2U2 keeps no stream's state, so the trace R2U2 reads must " \
           "carry the definition's values tick by tick" in err


def test_the_c_monitor_reads_the_variables_the_definition_reads(tmp_path):
    got, _err = _monitors(tmp_path, "whenever rise ctrl shall immediately satisfy o", "c")
    header = next(got["out"].glob("*.h")).read_text(encoding="utf-8")
    inputs = header.split("p_R1_inputs;")[0].rsplit("typedef struct {", 1)[1]
    assert "/* a: boolean" in inputs and "/* o: boolean" in inputs and "rise" not in inputs


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=10))
def test_the_monitor_steps_as_the_definition_written_out(tmp_path_factory, rows):
    tmp = tmp_path_factory.mktemp("m")
    defined = _monitors(tmp, "whenever rise ctrl shall immediately satisfy o")[0]
    written = _monitors(tmp, "whenever a & !preBool(false, a) ctrl shall immediately "
                             "satisfy o")[0]
    m, w = defined["MONITORS"]["R1"](), written["MONITORS"]["R1"]()
    samples = [{"a": a, "o": o} for a, o in rows]
    assert m.run(samples) == w.run(samples)
    assert (m.status, m.status_tick, m.finish()) == (w.status, w.status_tick, w.finish())
