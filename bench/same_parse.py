"""Same parse results as another checkout: every requirement of the given files read by this
tree's ``fretish.files.load_requirements`` and by the other's, compared entry by entry.

    python3 bench/same_parse.py --baseline DIR FILE [FILE ...]

DIR is another fretc checkout (e.g. ``git archive main | tar -x -C DIR``), imported as the
package ``fretish_baseline`` (as ``bench/bench_parse.py --baseline`` does). Per entry, the
id, text, position and attributes, and either the AST with every field and every span
(class names, not classes: the two trees' classes differ) or the error (message, file line
and column, the line shown) must be equal. Prints one count line per file and the first
differences; exits 1 when any entry differs. ``bench/parse_corpus.py`` writes files of many
good and bad sentences for it.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_parse import load_baseline  # noqa: E402
from fretc.fretish.files import load_requirements  # noqa: E402


def deep(x):
    """A comparable form of a value: dataclasses by class name and every field (spans
    included), named tuples (spans) by class name and items."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__,) + tuple((f.name, deep(getattr(x, f.name)))
                                           for f in dataclasses.fields(x))
    if isinstance(x, tuple) and hasattr(x, "_fields"):
        return (type(x).__name__,) + tuple(x)
    if isinstance(x, (tuple, list)):
        return tuple(deep(y) for y in x)
    if isinstance(x, BaseException):
        return (type(x).__name__, str(x), getattr(x, "line", None),
                getattr(x, "column", None), getattr(x, "text_line", None))
    return x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, required=True)
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    differ = 0
    with tempfile.TemporaryDirectory() as tmp:
        load_baseline(args.baseline, tmp)
        import fretish_baseline.files as base_files
        for f in args.files:
            ours = load_requirements([f])
            ref = base_files.load_requirements([f])
            same = errors = 0
            if len(ours) != len(ref):
                print(f"{f}: {len(ours)} entries here, {len(ref)} in the baseline")
                differ += 1
                continue
            for a, b in zip(ours, ref):
                if deep(a) == deep(b):
                    same += 1
                    errors += a.error is not None
                else:
                    differ += 1
                    if differ <= 5:
                        print(f"  differs: {a.id}: {a.text!r}")
            print(f"{f}: {len(ours)} entries, {same} identical ({errors} of them errors), "
                  f"{len(ours) - same} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    raise SystemExit(main())
