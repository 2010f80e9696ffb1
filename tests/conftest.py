"""Test configuration.

* The differential-test helpers in this folder are importable.
* fretc's disk cache (``common/cache.py``) goes to a folder of the system's temporary
  directory, one per user, unless ``FRETC_CACHE_DIR`` is already set: the suite must not
  write entries into the user's own cache (``~/.cache/fretc``). The folder is kept between
  runs, so a second run is warm as a user's would be; the tests of cold runs, damaged
  entries and read-only folders set ``FRETC_CACHE_DIR`` to their own ``tmp_path``. Set before
  any test runs, so the fretc subprocesses the tests start inherit it. The cache's seal key
  (kept outside the cache folder, in the user's state folder: ``~/.local/state/fretc``)
  goes likewise to a folder of the temporary directory, one per user, unless
  ``FRETC_STATE_DIR`` is already set: the suite must not write a key into the user's home.
* ``long``: the tests of 3 s or more listed in ``long_tests.txt``, left out of the default
  run (which must stay under 10 minutes on a 2-core machine) and run by CI in a step of
  their own (``-m long``).
* The default run (``-m 'not slow and not ray and not long'``, pyproject.toml) also takes a
  fixed sample of the cases of each parametrized ``slow`` test (:data:`SLOW_SAMPLE` of them, chosen by a hash
  of their names: the same in every run and xdist worker); ``-m slow`` runs them all.
* ``shared``: the project's shared data (``../shared``), or a skip with one reason when it is
  absent (``tests/_shared.py``; a user's clone has none).
* Hypothesis: no deadline and no "too slow" health check (profile ``fretc``): on a loaded
  2-core machine generating an example can take seconds, which says nothing about fretc.
"""
import os
import sys
import tempfile
import zlib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

sys.path.insert(0, str(Path(__file__).resolve().parent))

# the default profile draws the same examples every run (derandomize: a suite whose time and
# result do not depend on the draw, as CI needs); FRETC_HYPOTHESIS=random explores new ones
settings.register_profile("fretc", deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("fretc-random", deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("fretc-random" if os.environ.get("FRETC_HYPOTHESIS") == "random"
                      else "fretc")

import _shared  # noqa: E402

# the fretc subprocesses the tests start compile fretc's sources once, not each time: a
# PYTHONDONTWRITEBYTECODE set in the caller's environment would cost every one of them
# about 0.4 s of recompilation (13 % of the subprocess-heavy folders)
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

#: where the suite's fretc cache goes when the caller did not choose one
TEST_CACHE_DIR = os.path.join(tempfile.gettempdir(),
                              f"fretc-test-cache-{getattr(os, 'getuid', lambda: 0)()}")
os.environ.setdefault("FRETC_CACHE_DIR", TEST_CACHE_DIR)
#: where the suite's seal key of the cache goes (common/cache.py: never in the cache folder)
TEST_STATE_DIR = os.path.join(tempfile.gettempdir(),
                              f"fretc-test-state-{getattr(os, 'getuid', lambda: 0)()}")
os.environ.setdefault("FRETC_STATE_DIR", TEST_STATE_DIR)

#: cases of each parametrized slow test that the default run takes
SLOW_SAMPLE = 2


#: the tests marked ``long`` (tests/long_tests.txt: node ids, a case or every case)
LONG = frozenset(line.strip() for line in
                 (Path(__file__).parent / "long_tests.txt").read_text(encoding="utf-8").splitlines()
                 if line.strip() and not line.startswith("#"))


@pytest.hookimpl(tryfirst=True)  # before ``-m`` deselects the slow and long tests
def pytest_collection_modifyitems(config, items):
    """Mark the tests of :data:`LONG` ``long``; when ``-m`` leaves the slow tests out, keep a
    fixed sample of each parametrized one."""
    for item in items:
        if item.nodeid in LONG or item.nodeid.partition("[")[0] in LONG:
            item.add_marker(pytest.mark.long)
    if "not slow" not in (config.option.markexpr or ""):
        return
    cases: dict = {}
    for item in items:
        if getattr(item, "callspec", None) is not None and item.get_closest_marker("slow"):
            cases.setdefault((item.path, item.originalname), []).append(item)
    for (path, _), group in cases.items():
        # the cases of smallest hash: the same whatever other cases the test has
        group.sort(key=lambda item: zlib.crc32(f"{path.name}::{item.name}".encode()))
        for item in group[:SLOW_SAMPLE]:
            item.own_markers[:] = [m for m in item.own_markers if m.name != "slow"]


@pytest.fixture(scope="session")
def shared() -> Path:
    """The ../shared folder (FRET's vectors, the corpus, the real logs), or a skip."""
    _shared.skip_without_shared()
    return _shared.SHARED
