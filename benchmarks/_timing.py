"""
Timing shared by the benchmark scripts
======================================

-   :func:`interleaved_best`: best seconds per call of several cases measured in
    turns, so a change in the shared machine's load hits a case and its baseline alike.
-   :func:`environment`: the "environment" line every script prints first.

The scripts run as ``python benchmarks/bench_x.py`` (this folder is then first on
``sys.path``), so they import this module as ``_timing``.
"""

from __future__ import annotations

import math
import os
import platform
import time
import timeit
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["interleaved_best", "environment"]


def interleaved_best(cases: dict[str, Callable[[], object]], repeats: int, run_seconds: float,
                     clock: Callable[[], float] = time.perf_counter) -> dict[str, float]:
    """
    Best seconds per call of every case over ``repeats`` rounds; within a round the
    cases take turns, so a change in the machine's load hits numerator and
    denominator alike. Each case's loop count is set once (after a warm-up) so
    that one timed run lasts about ``run_seconds`` (at least one call). ``clock``: wall time
    by default, or e.g. ``time.process_time`` (the process's CPU time).
    """
    timers, numbers = {}, {}
    for name, fn in cases.items():
        timer = timeit.Timer(fn, timer=clock)
        number, elapsed = timer.autorange()  # also the warm-up
        timers[name] = timer
        numbers[name] = max(1, math.ceil(number * run_seconds / max(elapsed, 1e-9)))
    best = {name: math.inf for name in cases}
    for _ in range(repeats):
        for name, timer in timers.items():
            best[name] = min(best[name], timer.timeit(numbers[name]) / numbers[name])
    return best


def environment(**settings: Any) -> dict[str, Any]:
    """The "environment" record a script prints first: Python and numpy versions, CPUs, the 1-minute load
    average (None where the system has none), then the script's own ``settings``."""
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    return {"bench": "environment", "python": platform.python_version(), "numpy": np.__version__,
            "cpus": os.cpu_count(), "loadavg_1min": load, **settings}
