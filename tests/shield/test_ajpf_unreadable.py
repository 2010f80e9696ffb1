"""AJPF (long; ``tests/shield/test_ajpf_agent.py``'s MCAPL, built once into the suite's cache)
on a small agent whose environment may choose an input atom unreadable
(``N_env.unreadable``, :mod:`fretc.shield.emit_gwendolen`): the agent's machine decides such
a tick for every value the atom could have had, and G1's property still holds.

G1/G2 (``upon a`` for 3 ticks ``o``, ``whenever x > 2`` immediately ``!p``), ``x_gt_2``
unreadable, the controller proposing ``push`` only (the ``.ail``): the proposal that wants
``o`` false, the one G1 must override (``stop`` is the fallback's outputs). About 2 minutes
on 2 cores (61 JPF states; with ``stop`` too, 121 states and about 9 minutes).

No mutant here: G1's property is stated at its trigger's tick only (AJPF cannot count the
3 ticks), and a machine that keeps its state on a tick with an unknown atom still gives
``o`` there. On ``G3: upon a ctrl shall always satisfy q`` (stated exactly) such a machine's
Java gives ``q`` false the tick after ``a`` rose with ``x`` unreadable, yet AJPF reported G3
holding on that agent: the state the mutant reaches then is one JPF has already explored (the
machine forgot the trigger: the state of a run without it), and AJPF's search found no
accepting path through it. The mutant is caught by the differential instead
(``tests/shield/test_gwendolen_unreadable.py``).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

from test_ajpf_agent import ajpf, fretc_ajpf  # noqa: F401 (ajpf: the session's MCAPL)

G1_G2 = ("G1: upon a ctrl shall for 3 ticks satisfy o\n"
         "G2: whenever x > 2 ctrl shall immediately satisfy !p\n")


def unreadable_agent(folder: Path, base: str, text: str, outputs: str, label: str) -> Path:
    """``fretc shield BASE.fret --emit gwendolen -o folder`` (inputs ``a``, ``x``), property
    ``label``'s ``.ail`` given ``x_gt_2`` unreadable and the controller proposing ``push``."""
    folder.mkdir(parents=True)
    src = folder / f"{base}.fret"
    src.write_text(text, encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", str(src), "--inputs", "a,x", "--outputs",
                                    outputs, "--emit", "gwendolen", "-o", str(folder)])
    assert got.exit_code == 0, got.output
    ail = folder / f"{base}_{label}.ail"
    text_ail = ail.read_text(encoding="utf-8")
    ail.write_text(text_ail + f"{base}_env.unreadable = x_gt_2\n{base}_env.proposals = push\n",
                   encoding="utf-8")
    return folder


@pytest.mark.xdist_group("ajpf")
def test_g1_holds_when_x_may_be_unreadable(ajpf, tmp_path):  # noqa: F811
    folder = unreadable_agent(tmp_path / "g", "g", G1_G2, "o,p", "G1")
    got = fretc_ajpf(ajpf, folder, "G1")
    assert got.returncode == 0, got.stdout + got.stderr
    assert "  G1: holds (JPF states: new=" in got.stdout, got.stdout
