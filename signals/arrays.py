"""All ticks of one clock at once, as numpy arrays (:func:`sample_arrays`): the clock of
:func:`fretc.signals.sample` evaluated block by block (:func:`fretc.signals.
sample_blocks`) and joined; for tests, benchmarks and short logs."""

from __future__ import annotations

import numpy as np

from fretc.signals.bindings.spec import Bindings
from fretc.common.problems import SignalError
from fretc.logs import CSV_TOPIC, LogSource
from fretc.signals.blocks import blocks_of_ticks, sample_blocks
from fretc.signals.clock import sample

__all__ = ["SampledArrays", "sample_arrays"]


class SampledArrays(tuple):
    """``(times, columns)`` from :func:`sample_arrays`, with extra attributes.

    Attributes:
        times: int64 array of evaluated tick times (ns).
        columns: variable → 1-D array (bool or float64), one item per evaluated tick.
        warmup_ticks: ticks not evaluated (as :attr:`Sampling.warmup_ticks`).
        log_times: topic → int64 array, log time of the message held at each tick.
        vectorized: False when some binding was evaluated tick by tick (values that do not
            fit columns: ragged arrays, text).
    """

    warmup_ticks: int
    log_times: dict[str, np.ndarray]
    vectorized: bool

    def __new__(cls, times: np.ndarray, columns: dict[str, np.ndarray], warmup_ticks: int,
                log_times: dict[str, np.ndarray], vectorized: bool) -> SampledArrays:
        self = super().__new__(cls, (times, columns))
        self.warmup_ticks = warmup_ticks
        self.log_times = log_times
        self.vectorized = vectorized
        return self

    @property
    def times(self) -> np.ndarray:
        """int64 tick times (ns), evaluated ticks only."""
        return self[0]

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """Variable → 1-D bool/float64 array, one item per evaluated tick."""
        return self[1]


def sample_arrays(source: LogSource, bindings: Bindings | None = None) -> SampledArrays:
    """All evaluated ticks of :func:`fretc.signals.sample`'s clock at once.

    Returns:
        ``(times, columns)`` (a :class:`SampledArrays`): int64 tick times and variable →
        bool/float64 array; the values equal :func:`sample`'s.

    Raises:
        SignalError: as :func:`sample` (the first variable whose evaluation fails).
    """
    if source.kind == "csv" and (bindings is None or not bindings.variables):
        s = sample(source, bindings)
        names = list(source.columns)  # type: ignore[attr-defined]  # a CsvSource
        blocks = list(blocks_of_ticks(iter(s), names, [CSV_TOPIC]))
        return _joined(blocks, names, 0, True)
    if bindings is None:
        raise SignalError(f"{source.path}: a {source.kind} log needs bindings (signals are "
                          "declared, never guessed)")
    names = list(bindings.variables)
    g = sample_blocks(source, bindings, {0: (names, bindings.topics)})
    blocks = [blk for _key, blk in g]
    if g.errors.get(0) is not None:
        raise g.errors[0]
    if g.failed[0]:
        raise next(iter(g.failed[0].values()))
    return _joined(blocks, names, g.groups[0].warmup_ticks, not g.per_tick[0])


def _joined(blocks: list, names: list[str], warmup: int, vectorized: bool) -> SampledArrays:
    def cat(parts: list[np.ndarray], dtype) -> np.ndarray:
        if not parts:
            return np.zeros(0, dtype=dtype)
        if any(p.dtype != parts[0].dtype for p in parts):
            return np.concatenate([p.astype(np.float64) for p in parts])
        return np.concatenate(parts)

    times = cat([b.times for b in blocks], np.int64)
    columns = {n: cat([b.values[n] for b in blocks], np.float64) for n in names}
    topics = blocks[0].log_times if blocks else {}
    log_times = {t: cat([b.log_times[t] for b in blocks], np.int64) for t in topics}
    return SampledArrays(times, columns, warmup, log_times, vectorized)
