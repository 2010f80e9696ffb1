"""``python -m fretc`` is the ``fretc`` command."""
from .cli import main

main()
