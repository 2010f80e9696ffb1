"""A silence (a topic's publisher away, so nothing of it was sent: a watched run's
``publisher_left_for_good`` and ``publisher_absent`` gaps) leaves the topic's values unknown
but what ``age()`` reads known; every other gap leaves both unknown (audit/gaps.py)."""

from __future__ import annotations

import numpy as np
import pytest

from fretc.audit.gaps import unknown_masks
from fretc.logs.base import Gap
from fretc.logs.recorded_gaps import LEFT_FOR_GOOD, PUBLISHER_ABSENT, SILENT_CAUSES, losses
from fretc.signals.bindings.expression import age_only_topics
from fretc.signals.bindings.files import parse_bindings

BINDINGS = """[tick]
period = "100 ms"
[variables]
stale = "age(/scan) > 0.3"
near = "min(/scan.ranges) < 0.9"
both = "age(/scan) > 0.3 | min(/scan.ranges) < 0.9"
stop = "/ctl.data"
"""


def _bindings():
    return parse_bindings(BINDINGS, "t.bindings.toml")


def test_age_only_topics_are_those_read_through_age_alone():
    b = _bindings().variables
    assert age_only_topics(b["stale"].ast) == {"/scan"}
    assert age_only_topics(b["near"].ast) == set()
    assert age_only_topics(b["both"].ast) == set()  # its values too
    assert age_only_topics(b["stop"].ast) == set()


@pytest.mark.parametrize("cause", sorted(SILENT_CAUSES) + ["publisher_left", "undecodable"])
def test_a_silence_leaves_age_known_and_values_unknown(cause):
    times = np.arange(10, dtype=np.int64) * 100 + 1000
    held = np.where(times < 1300, times, 1300)  # /scan's last message at 1300: held after
    log_times = {"/scan": held, "/ctl": times}
    gaps = [Gap(1301, 2**63 - 1, frozenset({"/scan"}), cause)]
    masks = unknown_masks(times, log_times, ["stale", "near", "both", "stop"], _bindings(),
                          gaps)
    silent = cause in SILENT_CAUSES
    assert ("stale" in masks) == (not silent)
    assert masks["near"][times > 1300].all() and not masks["near"][times <= 1300].any()
    assert masks["both"][times > 1300].all()
    assert "stop" not in masks
    assert (losses(gaps) == []) == silent


def test_the_causes_of_a_silence():
    assert SILENT_CAUSES == {LEFT_FOR_GOOD, PUBLISHER_ABSENT}
