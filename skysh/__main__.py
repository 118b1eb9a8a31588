"""``python -m skysh``: the same command line as the ``skysh`` console script (:func:`skysh.app.cli.main`)."""

from __future__ import annotations

import sys

from skysh.app.cli import main

if __name__ == "__main__":
    sys.exit(main())
