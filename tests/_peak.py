"""The peak memory of a test's own child process. ``resource.getrusage(RUSAGE_SELF)
.ru_maxrss`` in a child started by ``subprocess`` counts, on Linux, the resident pages of the
parent it was forked from before it ran its program (a pytest worker of a whole run: hundreds
of MB), so a bound on it fails on a loaded run and passes alone. ``VmHWM`` of
``/proc/self/status`` is the peak of the program's own address space, reset when it starts."""

#: Python source that prints the process's peak resident set in KB (VmHWM; ru_maxrss where
#: /proc is not there): append it to a child's code
PEAK_KB = (
    "def _peak_kb():\n"
    "    try:\n"
    "        with open('/proc/self/status') as f:\n"
    "            for line in f:\n"
    "                if line.startswith('VmHWM:'):\n"
    "                    return int(line.split()[1])\n"
    "    except OSError:\n"
    "        pass\n"
    "    import resource\n"
    "    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n")


def traced_audit(plan, path) -> tuple:
    """(the audit of the log at ``path`` by ``plan``, the traced peak of Python's allocations
    during it in bytes: :mod:`tracemalloc`)."""
    import tracemalloc

    from fretc.audit import audit_log

    tracemalloc.start()
    try:
        la = audit_log(plan, str(path))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return la, peak
