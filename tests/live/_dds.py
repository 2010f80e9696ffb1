"""DDS domain ids for the live tests. Two tests on one domain at once hear each other's
publications (the loopback configuration finds peers on 127.0.0.1), and Cyclone DDS refuses
a second configuration of a domain a process already holds (DDS_RETCODE_PRECONDITION_NOT_MET).
So each pytest-xdist worker draws from ids of its own, in turn, and a test that configures a
domain in its own process does it through ``fretc.live.dds.idl_types.open_participant``, which
keeps one configuration per domain and process."""

import itertools
import os

_drawn = itertools.count()


def fresh_domain(first: int = 100, last: int = 230) -> int:
    """The next DDS domain id of this worker, in ``[first, last]`` (Cyclone DDS's and Fast
    DDS's default port mapping reaches 232): worker ``w`` of ``n`` draws ``first + w``,
    ``first + w + n``, ... and starts over when the range is used up, so no two workers ever
    draw the same id and one worker reuses an id only after all of its others."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    w = int(worker[2:]) if worker[2:].isdigit() else 0
    n = max(1, int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
    per_worker = max(1, (last - first + 1 - w + n - 1) // n)
    return first + w + n * (next(_drawn) % per_worker)
