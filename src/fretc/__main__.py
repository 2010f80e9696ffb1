"""``python -m fretc`` is the ``fretc`` command."""
from fretc.cli import main

main()
