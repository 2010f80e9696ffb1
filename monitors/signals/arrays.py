"""All ticks at once with numpy (:func:`sample_arrays`, for short logs): the bound fields
are read into per-message columns, the held message of each topic at each tick is found
with ``np.searchsorted``, and each binding is evaluated over all ticks; the values equal
those of :func:`monitors.signals.clock.sample` (same extraction, same operations)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from common.units import NS_PER_S

from ..bindings.expression import Field
from ..bindings.extract import Valid, make_extractor
from ..bindings.spec import Bindings
from common.problems import ProblemLog, SignalError
from ..sources.selective import install as install_selective
from ..sources import CSV_TOPIC, CsvSource, LogSource
from .clock import Tick, check_topics, csv_bindings_check, csv_period, feed, sample

__all__ = ["SampledArrays", "FieldColumns", "sample_arrays"]


class SampledArrays(tuple):
    """``(times, columns)`` from :func:`sample_arrays`, with extra attributes.

    Attributes:
        times: int64 array of evaluated tick times (ns).
        columns: variable → 1-D array (bool or float64), one item per evaluated tick.
        warmup_ticks: ticks not evaluated (as :attr:`Sampling.warmup_ticks`).
        log_times: topic → int64 array, log time of the message held at each tick.
        vectorized: False when the values came from the streaming path (see sample_arrays).
    """

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


class _Fallback(Exception):
    """The vectorized path cannot represent some field (ragged arrays, strings, errors)."""


class FieldColumns:
    """The value of each bound field at each evaluated tick, gathered from per-message
    columns (what :meth:`monitors.bindings.Binding.evaluate_columns` reads).

    Args:
        n: number of evaluated ticks.
        tick_times: int64 tick times (ns), length ``n``.
        per_topic_times: topic -> int64 times of its messages.
        idx: topic -> for each tick, the index of the message held (length ``n``).
        raw: (topic, field path) -> the field's value in each message of the topic.
    """

    def __init__(self, n: int, tick_times: np.ndarray, per_topic_times: dict[str, np.ndarray],
                 idx: dict[str, np.ndarray], raw: dict[tuple[str, tuple], list[Any]]) -> None:
        self.n = n
        self.tick_times = tick_times
        self.topic_times = per_topic_times
        self.idx = idx
        self.raw = raw
        self.cache: dict[tuple[str, tuple], Any] = {}

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        """The field ``path`` of ``topic`` at each tick (bool/float64 array, or :class:`Valid`
        of ticks × items); ``node`` names it in errors.

        Raises:
            _Fallback: values that do not fit a column (ragged arrays, strings).
        """
        key = (topic, path)
        if key in self.cache:
            return self.cache[key]
        values = self.raw[key]
        idx = self.idx[topic]
        if all(type(v) is bool for v in values):
            out: Any = np.array(values, dtype=np.bool_)[idx]
        elif all(type(v) in (bool, float) for v in values):
            out = np.array(values, dtype=np.float64)[idx]
        elif all(isinstance(v, Valid) for v in values):
            lengths = {v.data.shape[0] for v in values}
            kinds = {v.data.dtype == np.bool_ for v in values}
            if len(lengths) != 1 or len(kinds) != 1:
                raise _Fallback(f"{node.text()}: arrays of different lengths")
            data = np.stack([v.data for v in values])[idx]
            if any(v.mask is not None for v in values):
                mask = np.stack([v.mask if v.mask is not None else np.ones(v.data.shape, np.bool_)
                                 for v in values])[idx]
            else:
                mask = None
            out = Valid(data, mask)
        else:
            raise _Fallback(f"{node.text()}: values that are not numbers or arrays")
        self.cache[key] = out
        return out

    @property
    def tf(self) -> Any:
        """``tf()`` needs every message of /tf and /tf_static, not the held ones.

        Raises:
            _Fallback: always (the values come from the streaming path).
        """
        raise _Fallback("tf() reads every message of /tf and /tf_static")

    def age(self, topic: str) -> np.ndarray:
        """``age(topic)`` at each tick: seconds since the held message (float64)."""
        held = self.topic_times[topic][self.idx[topic]]
        return (self.tick_times - held).astype(np.float64) / NS_PER_S


def sample_arrays(source: LogSource, bindings: Bindings | None = None) -> SampledArrays:
    """All evaluated ticks at once, as numpy arrays (for short logs).

    Reads the bound topics into per-message columns, places the ticks, finds the held message
    of each topic at each tick with ``np.searchsorted``, and evaluates each binding with numpy
    over all ticks.  Values equal those of :func:`sample` (same extraction, same operations).
    When a field cannot be put in a column (arrays whose length changes between messages,
    strings, a field missing from some message) the values are taken from :func:`sample`
    instead (``vectorized`` is then False) so errors and results stay the same.

    Returns:
        ``(times, columns)`` (a :class:`SampledArrays`): int64 tick times and variable →
        bool/float64 array.

    Raises:
        SignalError: as :func:`sample`.
    """
    if source.kind == "csv":
        assert isinstance(source, CsvSource)
        return _arrays_csv(source, bindings)
    if bindings is None:
        raise SignalError(f"{source.path}: a {source.kind} log needs bindings (signals are declared, "
                          "never guessed)")
    topics = check_topics(source, bindings)
    install_selective(source, bindings)
    try:
        times, logs, raw = _read_columns(source, bindings, topics)
    except _Fallback:
        return _arrays_from_stream(source, bindings)
    all_times = [ts for ts in times.values() if ts]
    if not all_times:
        return SampledArrays(np.zeros(0, np.int64), {n: np.zeros(0) for n in bindings.variables}, 0,
                             {}, True)
    tick_times = _tick_times(bindings, times, all_times)
    topic_times = {t: np.array(v, dtype=np.int64) for t, v in times.items()}
    topic_logs = {t: np.array(v, dtype=np.int64) for t, v in logs.items()}
    idx_all = {t: np.searchsorted(topic_times[t], tick_times, side="right") - 1 for t in topics}
    if bindings.tick.topic is not None:  # a per-topic tick sees its own message of that topic
        idx_all[bindings.tick.topic] = np.arange(len(tick_times))
    ok = np.ones(len(tick_times), dtype=np.bool_)
    for t in bindings.topics:
        ok &= idx_all[t] >= 0
    warmup = int(len(tick_times) - ok.sum())
    tick_times = tick_times[ok]
    idx = {t: i[ok] for t, i in idx_all.items()}
    n = len(tick_times)
    columns: dict[str, np.ndarray] = {}
    if n:
        cols = FieldColumns(n, tick_times, topic_times, idx, raw)
        try:
            with np.errstate(all="ignore"):
                for name, b in bindings.variables.items():
                    columns[name] = b.evaluate_columns(cols)
        except _Fallback:
            return _arrays_from_stream(source, bindings)
    else:
        columns = {name: np.zeros(0) for name in bindings.variables}
    held = {t: topic_logs[t][idx[t]] for t in topics if len(topic_logs[t])}
    return SampledArrays(tick_times, columns, warmup, held, True)


def _read_columns(source: LogSource, bindings: Bindings, topics: set[str]
                  ) -> tuple[dict[str, list[int]], dict[str, list[int]],
                             dict[tuple[str, tuple], list[Any]]]:
    """One read of the bound topics: topic -> times, topic -> log times, and (topic, field
    path) -> the field's value in each message.

    Raises:
        _Fallback: a field that cannot be extracted from some message.
    """
    fields: dict[tuple[str, tuple], Any] = {}
    for b in bindings.variables.values():
        for f in b.fields:
            fields.setdefault((f.topic, f.path), make_extractor(f))
    by_topic: dict[str, list[tuple[tuple, Any]]] = {}
    for (topic, path), ex in fields.items():
        by_topic.setdefault(topic, []).append(((topic, path), ex))
    times: dict[str, list[int]] = {t: [] for t in topics}
    logs: dict[str, list[int]] = {t: [] for t in topics}
    raw: dict[tuple[str, tuple], list[Any]] = {k: [] for k in fields}
    for topic, t, log_time, data in feed(source, bindings, topics, ProblemLog()):
        times[topic].append(t)
        logs[topic].append(log_time)
        for key, ex in by_topic.get(topic, ()):
            try:
                raw[key].append(ex(data))
            except Exception as exc:
                raise _Fallback(str(exc)) from None
    return times, logs, raw


def _tick_times(bindings: Bindings, times: dict[str, list[int]], all_times: list[list[int]]
                ) -> np.ndarray:
    """int64 times of every tick (warm-up included): the fixed-period grid from the first to
    the last message, or the tick topic's message times."""
    start = min(ts[0] for ts in all_times)
    end = max(ts[-1] for ts in all_times)
    if bindings.tick.period_ns is not None:
        n_all = (end - start) // bindings.tick.period_ns + 1
        return start + bindings.tick.period_ns * np.arange(n_all, dtype=np.int64)
    return np.array(times[bindings.tick.topic], dtype=np.int64)


def _columns_of_ticks(ticks: list[Tick], names: Any) -> dict[str, np.ndarray]:
    """Variable -> array of its values at ``ticks`` (bool when every value is, else float64)."""
    columns = {}
    for name in names:
        vals = [t.values[name] for t in ticks]
        dtype = np.bool_ if vals and all(type(v) is bool for v in vals) else np.float64
        columns[name] = np.array(vals, dtype=dtype)
    return columns


def _arrays_from_stream(source: LogSource, bindings: Bindings) -> SampledArrays:
    s = sample(source, bindings)
    ticks = list(s)
    times = np.array([t.time for t in ticks], dtype=np.int64)
    columns = _columns_of_ticks(ticks, bindings.variables)
    topics = sorted({k for t in ticks for k in t.log_times})
    log_times = {k: np.array([t.log_times[k] for t in ticks], dtype=np.int64) for k in topics}
    return SampledArrays(times, columns, s.warmup_ticks, log_times, False)


def _arrays_csv(source: CsvSource, bindings: Bindings | None) -> SampledArrays:
    period = csv_period(source, bindings)
    source._begin_pass()
    rows = list(source.rows())
    times = np.array([r.time if r.time is not None else r.index * period for r in rows], dtype=np.int64)
    raw_cols = {}
    for c in source.columns:
        dtype = np.bool_ if source.types[c] == "bool" else np.float64
        raw_cols[c] = np.array([r.values[c] for r in rows], dtype=dtype)
    source.counts[CSV_TOPIC] = len(rows)
    if bindings is None or not bindings.variables:
        return SampledArrays(times, raw_cols, 0, {CSV_TOPIC: times}, True)
    csv_bindings_check(source, bindings)
    idx = {CSV_TOPIC: np.arange(len(rows))}
    raw: dict[tuple[str, tuple], list[Any]] = {}
    try:
        for b in bindings.variables.values():
            for f in b.fields:
                ex = make_extractor(f)
                raw[(f.topic, f.path)] = [ex(SimpleNamespace(**r.values)) for r in rows]
        cols = FieldColumns(len(rows), times, {CSV_TOPIC: times}, idx, raw)
        with np.errstate(all="ignore"):
            columns = {name: b.evaluate_columns(cols) for name, b in bindings.variables.items()}
    except Exception:
        columns = _columns_of_ticks(list(sample(source, bindings)), bindings.variables)
        return SampledArrays(times, columns, 0, {CSV_TOPIC: times}, False)
    return SampledArrays(times, columns, 0, {CSV_TOPIC: times}, True)
