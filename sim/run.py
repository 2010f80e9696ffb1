"""Record one scenario to an MCAP file (the library entry point behind ``python -m fretc.sim record``)."""

from __future__ import annotations

import io
from dataclasses import replace
from pathlib import Path
from typing import Any, BinaryIO, cast

from fretc.common.outputs import create_output, output_folder
from fretc.sim.faults import Fault
from fretc.sim.recording import McapRecorder
from fretc.sim.scenarios import Scenario, get_scenario
from fretc.sim.simulation import RunResult, Simulation


def record(scenario: str, seed: int = 1, output: str | Path | io.BufferedIOBase | None = None,
           ros1: bool = False, png: str | Path | None = None, threshold: float = 0.9,
           stop_delay: float | None = None, compression: str = "zstd",
           safety: str | None = None, faults: tuple[Fault, ...] = ()) -> RunResult:
    """Simulate ``scenario`` with ``seed`` and write the run to ``output`` (a path or a binary
    stream; ``None`` discards it), as ROS 2 (CDR) or, with ``ros1``, ROS 1 messages; draw it to
    ``png`` if given. ``threshold`` m is the SIF threshold, ``stop_delay`` s overrides the
    ``stop_delay`` scenario's delay; ``safety`` ``"shield:DIR"`` puts the shield generated in DIR
    in place of the hand-written SIF and interceptor (:mod:`fretc.sim.shielded`); ``faults``
    are injected besides the scenario's own (:class:`fretc.sim.faults.Fault`). Returns the
    :class:`~fretc.sim.simulation.RunResult`.

    Raises ``KeyError`` for an unknown scenario, ``ValueError`` for bad parameters (a
    ``safety`` that names no shield folder) and ``OSError`` if the output cannot be written.
    """
    sc = get_scenario(scenario, stop_delay)
    if faults:
        sc = replace(sc, faults=sc.faults + tuple(faults))
    result = record_scenario(sc, seed, output, ros1=ros1,
                             threshold=threshold, compression=compression,
                             shield=shield_of(safety))
    if png is not None:
        from fretc.sim.plot import draw_run  # lazy: matplotlib takes ~1 s to import, only for --png
        draw_run(result, png)
    return result


def shield_of(safety: str | None) -> Any:
    """The :class:`fretc.sim.shielded.ShieldedSafety` a ``--safety`` value names (None for
    the hand-written Safety System: ``None`` or ``"sif"``).

    Raises ``ValueError`` for another value or a folder that holds no shield."""
    if safety in (None, "sif"):
        return None
    from fretc.sim.shielded import SHIELD_PREFIX, ShieldedSafety  # lazy: only with a shield

    if not safety.startswith(SHIELD_PREFIX):
        raise ValueError(f"--safety is 'sif' (the hand-written SIF and interceptor) or "
                         f"'{SHIELD_PREFIX}DIR', not {safety!r}")
    return ShieldedSafety(safety[len(SHIELD_PREFIX):])


def record_scenario(sc: Scenario, seed: int = 1,
                    output: str | Path | io.BufferedIOBase | None = None, ros1: bool = False,
                    threshold: float = 0.9, compression: str = "zstd",
                    shield: Any = None) -> RunResult:
    """Simulate the scenario ``sc`` (for instance with :func:`fretc.sim.space.apply`'s parameters)
    and write the run to ``output`` as :func:`record` does; ``shield`` a
    :class:`fretc.sim.shielded.ShieldedSafety` in place of the SIF and interceptor.

    Raises ``ValueError`` for bad parameters and ``OSError`` if the output cannot be
    written."""
    sim = Simulation(sc, seed=seed, threshold=threshold, shield=shield)
    stream: BinaryIO
    if output is None:
        stream, close = io.BytesIO(), True
    elif isinstance(output, (str, Path)):
        output_folder(Path(output).parent)
        stream, close = create_output(output), True  # (a link planted there: replaced)
    else:
        stream, close = cast(BinaryIO, output), False
    try:
        rec = McapRecorder(stream, ros1=ros1, compression=compression)
        result = sim.run(rec)
        rec.finish()
    finally:
        if close:
            stream.close()
    return result
