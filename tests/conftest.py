"""Test configuration.

* The differential-test helpers in this folder are importable.
* fretc's disk cache (``common/cache.py``) goes to a folder of the system's temporary
  directory, one per user, unless ``FRETC_CACHE_DIR`` is already set: the suite must not
  write entries into the user's own cache (``~/.cache/fretc``). The folder is kept between
  runs, so a second run is warm as a user's would be; the tests of cold runs, damaged
  entries and read-only folders set ``FRETC_CACHE_DIR`` to their own ``tmp_path``. Set before
  any test runs, so the fretc subprocesses the tests start inherit it.
"""
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: where the suite's fretc cache goes when the caller did not choose one
TEST_CACHE_DIR = os.path.join(tempfile.gettempdir(),
                              f"fretc-test-cache-{getattr(os, 'getuid', lambda: 0)()}")
os.environ.setdefault("FRETC_CACHE_DIR", TEST_CACHE_DIR)
