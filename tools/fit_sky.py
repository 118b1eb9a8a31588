#!/usr/bin/env python
"""``python tools/fit_sky.py ...``: the same command as ``skysh fit`` (:mod:`skysh.app.fit_command`), from a checkout."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from skysh.app.fit_command import main

if __name__ == "__main__":
    sys.exit(main())
