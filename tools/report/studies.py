"""
The studies the report runs, imported in one place
==================================================

The sky-data experiments live in ``tools/studies/`` (out of the library: sky
sampling and SH in :mod:`studies.sky`, Table 3 in :mod:`studies.quantize_study`,
the irradiance reconstructions in :mod:`studies.hazel_study`) and their markdown
layouts in ``tools/quantize_experiment.py``. Every section imports them from
here, so a further move changes this module's imports only.
"""

from __future__ import annotations

from quantize_experiment import hazel_markdown, reconstruction_timings, table3_markdown
from studies.hazel_study import COMPARISON_THETA_NODES, COSTS, exact_irradiance, irradiance_comparison, irradiance_experiment
from studies.quantize_study import table3_experiment
from studies.seed_bound import min_bound
from studies.sky import sample_sky_parameters, sky_coefficients

__all__ = [
    "COMPARISON_THETA_NODES",
    "COSTS",
    "exact_irradiance",
    "hazel_markdown",
    "irradiance_comparison",
    "irradiance_experiment",
    "min_bound",
    "reconstruction_timings",
    "sample_sky_parameters",
    "sky_coefficients",
    "table3_experiment",
    "table3_markdown",
]

SKY_SOURCE: str = "runtime"
"""Sky data of the quantization study: the shipped runtime, named (never a silent fallback)."""
