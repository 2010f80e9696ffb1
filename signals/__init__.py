"""The tick clock: turn a log and its bindings into a sequence of FRET-variable valuations.

Semantics (all times integer ns):

* **Time base.**  ``bindings.time_base == "log"``: a message's time is its log time (MCAP
  ``log_time``, bag timestamp).  ``"header"``: its ``header.stamp``.  Header stamps need not
  arrive in order, so messages are buffered and released in stamp order once the newest stamp
  seen is ``header_lag_ns`` past them.  A stamp earlier than the previous one on the same topic
  is recorded as a ``header_backwards`` DataProblem (the message is still placed in stamp
  order); a message whose stamp is older than one already released is recorded as
  ``header_late`` and skipped (it would rewrite the past).  A bound topic whose messages have
  no header is an error under the header time base.
* **Ticks.**  Fixed period: ticks at ``start + k·period`` for k = 0, 1, ... while
  ``≤ end``, where start and end are the times of the first and last message read (bound
  topics and the tick topic only).  Per-topic: one tick per message of the tick topic, at
  that message's time; that tick sees *its own* message of the tick topic (so two messages
  at one time give two ticks, each with its message).
* **Sample and hold.**  At a tick at time t every (other) topic holds its latest message with
  time ≤ t (messages at exactly t count, the last one in log order when several share t);
  ``age(/topic)`` is ``(t - time of that message) / 1e9``.
* **Warm-up.**  A tick before every bound topic has a message is not evaluated and not
  yielded: it is counted in ``warmup_ticks``; ``first_time`` is the time of the first
  evaluated tick.  Evaluated ticks are numbered from 0.
* **CSV.**  One tick per row, no warm-up.  Time is the ``time`` column, or row index ×
  period (the binding's fixed period if given, else the source's, 1 s by default).  Without
  bindings the columns are the variables; with bindings, expressions read ``/csv.column``.

``sample()`` streams (memory flat in the log's length); ``sample_arrays()`` reads everything
and evaluates with numpy, giving the same values (tested).

Modules: :mod:`~fretc.signals.clock` (:class:`Tick`, :class:`Sampling`, :func:`sample`:
one log's clock), :mod:`~fretc.signals.groups` (:func:`sample_groups`: one clock per
requirement in one read), :mod:`~fretc.signals.arrays` (:func:`sample_arrays`: numpy).
"""

from __future__ import annotations

from fretc.signals.arrays import SampledArrays, sample_arrays
from fretc.signals.clock import Sampling, Tick, sample
from fretc.signals.groups import GroupSampling, sample_groups
from fretc.signals.blocks import TickBlock, blocks_of_ticks, sample_blocks

__all__ = ["Tick", "Sampling", "GroupSampling", "SampledArrays", "sample", "sample_groups",
           "sample_arrays", "TickBlock", "sample_blocks", "blocks_of_ticks"]
