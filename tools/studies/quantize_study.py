"""
The Table 3 of Wiederien and Sloan (2024) on sky data
=====================================================

The seed's Table 3 (seed 002) measures the compression error of the codec with
the prior bound sqrt(5) and the tight bound sqrt(15)/2 on a light-probe set;
:func:`table3_experiment` runs the same measurement
(:func:`skysh.post.quantize.table3_errors`) on Preetham skies spread over the fitted
domain, and :func:`l1_rule_check` measures how converged its L1 quadrature is.
``tools/quantize_experiment.py`` prints both.
"""

from __future__ import annotations

from typing import Any

from skysh.post import quantize
from studies.sky import sample_sky_parameters, sky_coefficients

__all__ = ["table3_experiment", "l1_rule_check"]


def table3_experiment(n_points: int = 1024, seed: int | None = 0, bits: int = quantize.DEFAULT_BITS, source: str = "runtime",
                      n_theta: int = quantize.TABLE3_THETA_NODES) -> dict[str, Any]:
    """
    The seed's Table 3 on sky data: :func:`skysh.post.quantize.table3_errors` over many sky points.

    Parameters
    ----------
    n_points, seed
        Number and seed of the (sun zenith, sun azimuth, turbidity) points
        (:func:`studies.sky.sample_sky_parameters`).
    bits, n_theta
        As in :func:`skysh.post.quantize.table3_errors`.
    source
        As in :func:`studies.sky.sky_coefficients`: ``"runtime"`` or ``"reference"``.

    Returns
    -------
    dict
        The result of :func:`skysh.post.quantize.table3_errors` plus ``"source"``,
        ``"points"`` and ``"seed"``.
    """
    ts, az, t = sample_sky_parameters(n_points, seed)
    coeffs, used = sky_coefficients(ts, t, az, source=source)
    result = quantize.table3_errors(coeffs, bits=bits, n_theta=n_theta)
    result.update({"source": used, "points": int(n_points), "seed": seed})
    return result


def l1_rule_check(n_points: int = 64, seed: int | None = 0, bits: int = quantize.DEFAULT_BITS, source: str = "runtime",
                  n_theta: int = quantize.TABLE3_THETA_NODES) -> float:
    """
    Largest relative change of a Table 3 L1 sum from ``n_theta`` to ``2 n_theta`` Gauss nodes.

    Parameters
    ----------
    n_points, seed, bits, source, n_theta
        As in :func:`table3_experiment` (fewer points by default: the doubled rule
        costs four times as much).

    Returns
    -------
    float
        ``max |L1(n_theta) - L1(2 n_theta)| / L1(2 n_theta)`` over the eight rows: the
        quadrature error of the L1 column (|error| has kinks where the error changes
        sign, so its sphere rule is not exact; the L2 column is).
    """
    ts, az, t = sample_sky_parameters(n_points, seed)
    coeffs, _ = sky_coefficients(ts, t, az, source=source)
    coarse = quantize.table3_errors(coeffs, bits=bits, n_theta=n_theta)["rows"]
    fine = quantize.table3_errors(coeffs, bits=bits, n_theta=2 * n_theta)["rows"]
    return max(abs(a["L1"] - b["L1"]) / b["L1"] if b["L1"] > 0.0 else 0.0 for a, b in zip(coarse, fine, strict=True))
