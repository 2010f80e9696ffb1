"""audit.columns: a topic's held log times kept as the ticks' times while they are equal,
and as a column of their own from the first block where they differ (the blocks before it
restored), always the concatenation of the blocks' log times."""

from __future__ import annotations

import numpy as np

from fretc.audit.columns import TickColumns
from fretc.signals.blocks import TickBlock


def _block(start, times, held):
    return TickBlock(start, np.array(times, np.int64), {"x": np.ones(len(times), np.bool_)},
                     {"/a": np.array(held, np.int64)})


def test_log_times_equal_to_the_times_share_their_array():
    c = TickColumns(["x"], ["/a"])
    c.append_block(_block(0, [1, 2], [1, 2]))
    c.append_block(_block(2, [3, 4], [3, 4]))
    times, _cols, lts = c.finish()
    assert lts["/a"] is times
    assert times.tolist() == [1, 2, 3, 4]


def test_log_times_that_differ_later_are_a_column_of_their_own():
    c = TickColumns(["x"], ["/a", "/b"])
    c.append_block(_block(0, [1, 2], [1, 2]))
    c.append_block(_block(2, [3, 4], [3, 3]))
    c.append_block(_block(4, [5, 6], [5, 6]))
    times, _cols, lts = c.finish()
    assert times.tolist() == [1, 2, 3, 4, 5, 6]
    assert lts["/a"] is not times and lts["/a"].tolist() == [1, 2, 3, 3, 5, 6]
    assert lts["/b"].tolist() == [-1] * 6  # (a topic absent from the blocks: none held)
