"""``python -m mi_brdfs`` is the ``mi-brdfs`` command."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
