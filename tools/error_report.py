"""
The skysh error report: every accuracy, cost and stability figure in one run
============================================================================

Writes ``DIR/report.md`` with PNG charts (matplotlib, Agg) and the tables behind
them; every number is computed by the run that writes it. The sections live in
``tools/report/`` (one module each; ``--help`` lists them); this file is the
command line that ``skysh report`` also runs.

Run::

    python tools/error_report.py --out /tmp/report --quick      # every section, small sizes
    python tools/error_report.py --out docs/report              # the committed report
    python tools/error_report.py --out /tmp/r --sections 5,9    # some sections

A section that needs an optional package which is not installed (section 11:
cvxpy, the tools extra) is skipped: one line on stderr before any work, and
report.md says so under its heading, in the summary table and in the section list
(package, extra, ``pip install -e ".[tools]"``); the rest completes, exit status 0.

``--quick`` uses small grids and few samples (the test suite's smoke run); the
full run takes minutes on 2 cores, with progress bars. BLAS is limited to one
thread per process (multi-threaded OpenBLAS on a loaded 2-core machine turns a
0.2 s least-squares fit into 15 s); at most ``--jobs`` (default 2) worker
processes project the sky.
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # before numpy is imported, here and in the workers

TOOLS = Path(__file__).resolve().parent
for _path in (TOOLS.parent, TOOLS):  # the package of a source checkout, and tools/ (report/, fit_sky.py, ...)
    if str(_path) not in sys.path:
        sys.path.insert(0, str(_path))

main = importlib.import_module("report.run").main  # after tools/ is on the path
"""``main(argv) -> int``: run the report (``skysh report`` calls it)."""

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
