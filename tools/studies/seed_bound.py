"""
The deringing seed's conservative bound of a 3-band minimum, kept for comparison
================================================================================

Sloan (2017), "Deringing Spherical Harmonics" (seed 000), section 2.3: the bound the seed
decides its windows on. :mod:`skysh.post.dering` decides on the exact minimum
(:func:`skysh.sh.minimum.exact_min`) instead; this faithful version stays as a study, for
the error report's chart of its slack (``tools/report/s05_dering.py``) and
``tools/dering_experiment.py``.

-   :func:`min_bound`: the seed's bound, batched, in the sign convention of
    ``docs/conventions.md``; derivation in ``docs/dering.md``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_coeffs
from skysh.sh import minimum as shmin

__all__ = ["min_bound"]


def min_bound(coeffs: ArrayLike) -> NDArray[np.float64] | float:
    """
    The seed's conservative lower bound of a 3-band function's minimum (section 2.3).

    Parameters
    ----------
    coeffs
        Shape (9,), (9, C) or (..., 9, C), any unit.

    Returns
    -------
    float or ndarray
        Per channel ((9,): a float). Never above the minimum; equal to it for functions zonal
        about their optimal linear direction. For comparison only (deringing uses exact_min).

    Notes
    -----
    The seed's steps (optimal linear direction to +Z; eq. 3 exact; eqs. 4 and 5 at their worst
    phase), minimised over z exactly as a 2-D trust-region problem: ``docs/dering.md``.
    """
    c, vector, _ = check_coeffs(coeffs, high=3)
    if c.shape[-2] != 9:
        raise ValueError(f"coeffs must have 9 coefficients (3 bands) on axis -2, got {c.shape[-2]}")
    t, e, _ = shmin.normalised(np.moveaxis(c, -2, -1))
    q = t @ shmin.FORM_MAP
    g = q[..., 1:4]
    b = np.linalg.norm(g, axis=-1)
    v = np.where(b[..., None] > 0.0, g / np.where(b > 0.0, b, 1.0)[..., None], np.array([0.0, 0.0, 1.0]))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    frame = np.stack([*shmin.tangent_frame(v), v], -1)  # columns e1, e2, v
    r = np.swapaxes(frame, -1, -2) @ q[..., 4:].reshape(q.shape[:-1] + (3, 3)) @ frame
    zon = r[..., 2, 2]
    t2, s = np.hypot(0.5 * (r[..., 0, 0] - r[..., 1, 1]), r[..., 0, 1]), 2.0 * np.hypot(r[..., 0, 2], r[..., 1, 2])
    m2 = np.stack([np.stack([1.5 * zon + t2, -0.5 * s], -1), np.stack([-0.5 * s, np.zeros_like(s)], -1)], -2)
    val = np.ldexp(shmin.trust_region_min(q[..., 0] - 0.5 * zon - t2, np.stack([b, np.zeros_like(b)], -1), m2)[0], e)
    return float(val[0]) if vector else val
