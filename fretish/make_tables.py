"""Write the FRETish parser's tables shipped with fretc (``fretish/grammar_tables.json``,
:data:`fretc.fretish.parser.TABLES_FILE`), after an edit of ``grammar.lark`` or a new Lark:

    python -m fretc.fretish.make_tables

The tables are read on a first run (an empty cache folder) instead of being built from the
grammar (about 0.4 s of CPU; :mod:`fretc.common.lark_tables`), when they were made from the
same grammar, options and Lark version; otherwise the parser builds them as before.
``tests/fretish/test_shipped_tables.py`` fails when they are not those of the grammar.
"""

from __future__ import annotations

import sys

from fretc.common.outputs import write_file
from fretc.fretish.parser import TABLES_FILE, tables_text

__all__ = ["main"]


def main() -> int:
    """Write :data:`~fretc.fretish.parser.TABLES_FILE`; exit code 0."""
    write_file(TABLES_FILE, tables_text())
    print(f"wrote {TABLES_FILE}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
