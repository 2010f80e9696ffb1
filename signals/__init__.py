"""The tick clock: turn a log and its bindings into a sequence of FRET-variable valuations.

Semantics (all times integer ns):

Design notes: ARCHITECTURE.md, `signals/__init__.py`."""

from __future__ import annotations

from fretc.signals.arrays import SampledArrays, sample_arrays
from fretc.signals.clock import Sampling, Tick, sample
from fretc.signals.groups import GroupSampling, sample_groups
from fretc.signals.blocks import TickBlock, blocks_of_ticks, sample_blocks

__all__ = ["Tick", "Sampling", "GroupSampling", "SampledArrays", "sample", "sample_groups",
           "sample_arrays", "TickBlock", "sample_blocks", "blocks_of_ticks"]
