"""
Start-up cost of ``skysh coeffs`` against ``import numpy``
==========================================================

The issue's budget: ``skysh coeffs ...`` end to end (a new interpreter, argument
parsing, ``SkySH.load()``, one coefficients call, printing the table) within
3x the wall time of ``python -c "import numpy"``. Both are measured in one run,
taking turns, each the best of ``--repeats`` fresh subprocesses (after one
warm-up of each, so the file cache is warm), so the ratio holds on any machine:

-   ``numpy``: ``python -c "import numpy"``.
-   ``skysh coeffs (python -m)``: ``python -m skysh coeffs --sun-zenith 30
    --sun-azimuth 45 --turbidity 3`` (default format, sRGB).
-   ``skysh coeffs (console script)``: the installed ``skysh`` script with the
    same arguments, when it is on PATH (its launcher adds a little).
-   ``import skysh; SkySH.load()``: the library alone, for reference.

Prints one JSON line per case, e.g.::

    {"bench": "startup", "case": "skysh coeffs (python -m)", "seconds": ..., "reference": "numpy",
     "ratio": ..., "budget": 3.0}

Run: ``PYTHONPATH=. python benchmarks/bench_startup.py [--repeats 9]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT: Path = Path(__file__).resolve().parent.parent
"""The repository root (put on PYTHONPATH of the subprocesses)."""

BUDGET: float = 3.0
"""The issue's budget: skysh coeffs wall time / import numpy wall time."""

COEFFS_ARGS: tuple[str, ...] = ("coeffs", "--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3")
"""The timed command line (default format and colourspace)."""


def commands() -> dict[str, list[str]]:
    """The timed command lines by case name; the console script only when installed."""
    cases = {
        "numpy": [sys.executable, "-c", "import numpy"],
        "skysh coeffs (python -m)": [sys.executable, "-m", "skysh", *COEFFS_ARGS],
        "import skysh; SkySH.load()": [sys.executable, "-c", "from skysh import SkySH; SkySH.load()"],
    }
    script = shutil.which("skysh")
    if script is not None:
        cases["skysh coeffs (console script)"] = [script, *COEFFS_ARGS]
    return cases


def best_times(cases: dict[str, list[str]], repeats: int) -> dict[str, float]:
    """Best wall time of each case over ``repeats`` rounds (cases take turns within a round)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    best = {name: math.inf for name in cases}
    for round_ in range(repeats + 1):
        for name, argv in cases.items():
            t0 = time.perf_counter()
            subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
            elapsed = time.perf_counter() - t0
            if round_:  # round 0 warms the file cache
                best[name] = min(best[name], elapsed)
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--repeats", type=int, default=9, help="rounds; each case's best is kept (default 9)")
    args = parser.parse_args(argv)
    best = best_times(commands(), max(1, args.repeats))
    reference = best["numpy"]
    for name, seconds in best.items():
        print(json.dumps({
            "bench": "startup", "case": name, "seconds": round(seconds, 4), "reference": "numpy",
            "ratio": round(seconds / reference, 3), "budget": BUDGET if name.startswith("skysh coeffs") else None,
        }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
