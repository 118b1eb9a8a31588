"""
Offline: the best non-negative 3-band irradiance of the sky (issue 18)
======================================================================

Per (sun zenith, turbidity), the 3-band irradiance coefficients that are closest
to the true sky irradiance (in L2 or in the worst case over normals) subject to
being **non-negative on the whole sphere**, certified by a 4x4 matrix inequality
(below). An offline module for ``tools/irradiance_study.py`` and the fit tool:
the runtime never imports it, and cvxpy (the ``tools`` extra; solver Clarabel)
is imported inside the functions that solve.

-   :func:`quadratic_parts`: (c, g, A) of f(w) = c + g.w + w^T A w from 9 SH coefficients.
-   :func:`lifted_matrix`: the 4x4 matrix M(mu) whose PSD-ness certifies f >= 0.
-   :func:`sphere_minimum`: the exact minimum of a 3-band function on the sphere.
-   :func:`true_irradiance`: the sky's converged irradiance coefficients (many bands).
-   :func:`half_sphere_normals`: the normals the worst-case objectives are taken over.
-   :func:`constrained_coefficients`: one sky's constrained optimum, every channel.
-   :func:`constrained_point`: the same from (sun zenith, turbidity); process-pool friendly.
-   :func:`constrained_irradiance_grid`: the optimum over a (sun zenith, turbidity) grid.
-   :func:`fit_irradiance_table`, :func:`evaluate_irradiance_table`: the optimum as a
    Chebyshev table in the sky table's form (:mod:`skysh.fit`).

Coefficients are **irradiance** SH (E(l, m) = A_l L(l, m), cd/m^2 x sr, linear RGB)
in the layout of ``docs/conventions.md`` (real, orthonormal, Condon-Shortley phase,
index l (l + 1) + m), shaped (9, 3); :func:`radiance_equivalent` divides by A_l.

The certificate (S-lemma for one quadratic equality)
----------------------------------------------------
With the closed forms of the convention's table (k1 = sqrt(3) / (2 sqrt(pi)),
K1 = sqrt(15) / (2 sqrt(pi)), K0 = sqrt(5) / (4 sqrt(pi)), K2 = sqrt(15) / (4 sqrt(pi)),
Y00 = 1 / (2 sqrt(pi)); note the minus signs of the Condon-Shortley phase)::

    f(w) = Y00 e0 - k1 e1 y + k1 e2 z - k1 e3 x + K1 e4 xy - K1 e5 yz
           + K0 e6 (3 z^2 - 1) - K1 e7 xz + K2 e8 (x^2 - y^2)
         = c + g.w + w^T A w,
    c = Y00 e0 - K0 e6,   g = k1 (-e3, -e1, e2),
    A = [[ K2 e8,     K1 e4 / 2, -K1 e7 / 2],
         [ K1 e4 / 2, -K2 e8,    -K1 e5 / 2],
         [-K1 e7 / 2, -K1 e5 / 2, 3 K0 e6  ]].

For any real mu and |w| = 1, mu (1 - |w|^2) = 0, so f(w) = (1, w) M(mu) (1, w)^T with
``M(mu) = [[c + mu, g^T / 2], [g / 2, A - mu I]]``. Hence

*   **sufficient**: M(mu) PSD for some mu => f >= 0 on the sphere;
*   **necessary**: by the Schur complement, M(mu) is PSD iff mu <= lambda_1 = lambda_min(A)
    and d(mu) = c + mu - g^T (A - mu I)^+ g / 4 >= 0 (g in the range of A - mu I).
    d is the Lagrange dual function of min_{|w|=1} f (the minimum over R^3 of the
    convex function c + mu + g.w + w^T (A - mu I) w). There is no duality gap: write
    A = Q diag(lambda) Q^T, h = Q^T g, and w(mu) = -(A - mu I)^{-1} g / 2, whose norm
    grows monotonically on mu < lambda_1. If |w(mu)| reaches 1 at some mu*, w(mu*) is
    on the sphere and minimises the convex function over all of R^3, so
    min_sphere f <= f(w(mu*)) = d(mu*) <= min_sphere f. Otherwise (the "hard case": h
    has no component on lambda_1's eigenvectors q1 and |w(lambda_1)| < 1) take
    mu = lambda_1 and w = w(lambda_1) + tau q1 with |w| = 1: the convex function is
    flat along q1, so this is again a global minimiser on the sphere. Thus
    max_mu d(mu) = min_sphere f (More and Sorensen 1983; Stern and Wolkowicz 1995;
    the S-lemma with an equality, Polik and Terlaky 2007), and f >= 0 on the sphere
    iff some M(mu) is PSD: exact, not a relaxation.

A margin s (f >= s on the sphere) is the same statement for f - s, i.e. M(mu) - s
e_0 e_0^T PSD; :func:`constrained_coefficients` uses s = margin x mean(f) with
mean(f) = Y00 e0, linear in the unknowns. :func:`sphere_minimum` evaluates max_mu d(mu)
itself by bisection on the secular equation |w(mu)| = 1 (a valid lower bound at
every step, by weak duality).

Colour
------
The CIE 1976 chromaticity of XYZ is u' = 4X / D, v' = 9Y / D with D = X + 15Y + 3Z
(CIE 15:2004). For the truth's (u'_t, v'_t) at a normal and a reconstruction
XYZ_r (linear in the unknowns) with D_r > 0, the u'v' distance is
|(4X_r - u'_t D_r, 9Y_r - v'_t D_r)| / D_r; so "distance <= eps" is exactly the
second-order cone |(4X_r - u'_t D_r, 9Y_r - v'_t D_r)| <= eps D_r (which also
forces D_r >= 0): convex, linear in the three channels together.
:attr:`Objective.chroma` imposes it at the lit optimisation normals.

Symmetry: with the sun at azimuth 0 the sky, hence its irradiance, is symmetric in
y -> -y, and so are both objectives and the constraint; the problems are convex,
so a symmetrised optimum is optimal and the solutions are sought with the m < 0
coefficients (odd in y) at zero: 6 unknowns per channel, the rows of
:data:`HALF_ROWS` (the m >= 0 layout of the fitted tables).

References
----------
-   Ramamoorthi, R., Hanrahan, P. (2001): the clamped-cosine factors A_l.
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000): section 2.3.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eq. (1), the tabulated form.
-   More, J. J., Sorensen, D. C. (1983). Computing a Trust Region Step. SIAM J. Sci. Stat. Comput. 4(3).
-   Stern, R. J., Wolkowicz, H. (1995). Indefinite trust region subproblems... SIAM J. Optim. 5(2).
-   Polik, I., Terlaky, T. (2007). A Survey of the S-Lemma. SIAM Review 49(3).
-   CIE 15:2004 Colorimetry, section 8.1 (u', v').
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import fit, preetham, sh
from skysh._checks import as_float_array, check_bands, check_choice, check_range

__all__ = [
    "Y00", "K_LINEAR", "K_PRODUCT", "K_ZONAL", "K_SECTORAL", "LOBE", "HALF_ROWS", "LIFT_MAP", "MU_MATRIX",
    "METHODS", "TRUTH_BANDS", "TRUTH_THETA_NODES", "OPTIMISATION_NORMALS", "LP_EXPONENT", "BLEND_WEIGHT",
    "CHROMA_FLOOR", "Objective", "RECOMMENDED", "quadratic_parts", "lifted_matrix", "sphere_minimum", "radiance_equivalent",
    "true_irradiance", "half_sphere_normals", "constrained_coefficients", "constrained_point",
    "constrained_irradiance_grid", "fit_irradiance_table", "evaluate_irradiance_table",
]

Y00: float = 0.5 / math.sqrt(math.pi)
"""Y(0, 0) = 1 / (2 sqrt(pi)); the mean of a function over the sphere is Y00 e0."""

K_LINEAR: float = math.sqrt(3.0) / (2.0 * math.sqrt(math.pi))
"""|Y(1, m)| per Cartesian component: sqrt(3) / (2 sqrt(pi))."""

K_PRODUCT: float = math.sqrt(15.0) / (2.0 * math.sqrt(math.pi))
"""Factor of xy, yz, xz in Y(2, -2), Y(2, -1), Y(2, 1): sqrt(15) / (2 sqrt(pi))."""

K_ZONAL: float = math.sqrt(5.0) / (4.0 * math.sqrt(math.pi))
"""Factor of (3 z^2 - 1) in Y(2, 0): sqrt(5) / (4 sqrt(pi))."""

K_SECTORAL: float = math.sqrt(15.0) / (4.0 * math.sqrt(math.pi))
"""Factor of (x^2 - y^2) in Y(2, 2): sqrt(15) / (4 sqrt(pi))."""

LOBE: NDArray[np.float64] = sh.cosine_lobe(3)[np.repeat(np.arange(3), 2 * np.arange(3) + 1)]
"""(9,) clamped-cosine factor A_l of every 3-band coefficient (pi, 2 pi / 3 x 3, pi / 4 x 5)."""
LOBE.flags.writeable = False

HALF_ROWS: tuple[int, ...] = (0, 2, 3, 6, 7, 8)
"""Flat indices of the m >= 0 coefficients (0,0), (1,0), (1,1), (2,0), (2,1), (2,2):
the layout of :func:`skysh.coefficient_file.zonal_half_layout` (3)."""


def _lift_map() -> NDArray[np.float64]:
    """(9, 4, 4): M(mu) = sum_i e_i LIFT_MAP[i] + mu MU_MATRIX, rows/columns ordered (1, x, y, z)."""
    m = np.zeros((9, 4, 4))
    m[0, 0, 0] = Y00
    m[1, 0, 2] = m[1, 2, 0] = -K_LINEAR / 2.0  # g_y = -k1 e1
    m[2, 0, 3] = m[2, 3, 0] = K_LINEAR / 2.0  # g_z = k1 e2
    m[3, 0, 1] = m[3, 1, 0] = -K_LINEAR / 2.0  # g_x = -k1 e3
    m[4, 1, 2] = m[4, 2, 1] = K_PRODUCT / 2.0  # K1 e4 xy
    m[5, 2, 3] = m[5, 3, 2] = -K_PRODUCT / 2.0  # -K1 e5 yz
    m[6, 0, 0], m[6, 3, 3] = -K_ZONAL, 3.0 * K_ZONAL  # K0 e6 (3 z^2 - 1)
    m[7, 1, 3] = m[7, 3, 1] = -K_PRODUCT / 2.0  # -K1 e7 xz
    m[8, 1, 1], m[8, 2, 2] = K_SECTORAL, -K_SECTORAL  # K2 e8 (x^2 - y^2)
    m.flags.writeable = False
    return m


LIFT_MAP: NDArray[np.float64] = _lift_map()
"""(9, 4, 4) constant matrices: f(w) = (1, w) [sum_i e_i LIFT_MAP[i]] (1, w)^T for every w."""

MU_MATRIX: NDArray[np.float64] = np.diag([1.0, -1.0, -1.0, -1.0])
"""The multiplier's matrix in M(mu): mu (1 - |w|^2) = (1, w) MU_MATRIX (1, w)^T * mu."""
MU_MATRIX.flags.writeable = False

METHODS: tuple[str, ...] = ("l2", "minimax", "minimax_free", "lp", "blend")
"""Objectives: ``"l2"`` closest in L2 (coefficient distance; Parseval) subject to f >=
margin x mean; ``"minimax"`` smallest worst error over the normals subject to the same;
``"minimax_free"`` the same without the constraint (the floor of three bands);
``"lp"`` the L_p norm (p = :data:`LP_EXPONENT`) of the error over the normals,
subject to the constraint: a smooth, strictly convex blend between L2 and minimax;
``"blend"`` the worst error plus ``weight`` times the squared relative RMS error
over the sphere (from the coefficients, by Parseval), subject to the constraint:
strictly convex, hence a unique optimum that moves continuously with the sky."""

BLEND_WEIGHT: float = 1.0
"""Default weight of the squared relative RMS error in the ``"blend"`` objective."""

TRUTH_BANDS: int = 32
"""Bands of the true irradiance the worst-case objectives are taken against. Its
tail (A_l ~ l^-2.5 times the sky's slowly falling coefficients: the sky jumps to
zero at the horizon) leaves at most about 5e-4 of the mean irradiance against 64
bands, at the normals next to the nadir (``tools/irradiance_study.py`` prints the
convergence table); a worst-case error of several percent is not moved by that."""

TRUTH_THETA_NODES: int = 40
"""Zenith nodes per panel of the sky quadrature for :data:`TRUTH_BANDS` bands: within
about 1e-7 of the mean irradiance of the default 64 nodes at 32 bands (printed by the
study), at a third of the cost."""

OPTIMISATION_NORMALS: int = 4096
"""Fibonacci-sphere size whose y >= 0 half (plus the poles) carries the worst-case
objectives and the colour constraint: about 2,050 normals, about 3.2 degrees apart.
The study measures on 12,168 other normals, so its figures include what falls
between these."""

CHROMA_FLOOR: float = 0.05
"""The colour constraint applies where the true luminance irradiance is at least this
fraction of its mean: below it (next to the nadir, where the truth falls to 0) a
surface receives less than a twentieth of the average light and its chromaticity
is ill-conditioned."""

LP_EXPONENT: int = 8
"""Exponent p of the ``"lp"`` blend: large enough to weigh the worst normals, small
enough to stay smooth in the sky's parameters."""

_BISECTION_STEPS: int = 200
"""Bisection steps of :func:`sphere_minimum` on its bracket of width |g| / 2 <= 1 (the
function scaled by its largest coefficient): the bracket ends at adjacent floats, or
narrower than 2^-200 (1e-60), where d's error is below any rounding."""

_SOLVER_OPTIONS: dict[str, Any] = {}
"""Clarabel's defaults (gap and feasibility tolerances 1e-8 on the problem scaled so the
true mean irradiance is 1): far below every figure the study prints. Tighter (1e-9)
ends "optimal_inaccurate" on some worst-case problems, whose optimum sits on a face
of many active normals."""

_REPAIR_LIMIT: float = 1e-6
"""Largest constraint shortfall (of the mean) that :func:`constrained_coefficients`
repairs by raising e0; a larger one is a solver failure (RuntimeError)."""


# --------------------------------------------------------------------------- #
# The quadratic form, the certificate and the exact minimum
# --------------------------------------------------------------------------- #
def _as_coeffs(coeffs: ArrayLike, name: str = "coeffs") -> tuple[NDArray[np.float64], bool]:
    """(..., 9, C) float array from (9,) or (..., 9, C); flag whether the input was (9,)."""
    c = as_float_array(coeffs, name)
    vector = c.ndim == 1
    if vector:
        c = c[:, None]
    if c.ndim < 2 or c.shape[-2] != 9:
        raise ValueError(f"{name} must have shape (9,) or (..., 9, C) (3-band SH), got {c.shape}")
    return c, vector


def quadratic_parts(coeffs: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    """
    The polynomial form f(w) = c + g.w + w^T A w of 3-band SH (closed forms in the module docstring).

    Parameters
    ----------
    coeffs
        (9,) or (..., 9, C) coefficients (any unit).

    Returns
    -------
    c, g, A
        Shapes (..., C), (..., C, 3) and (..., C, 3, 3) (without the C axis for (9,) input).
    """
    e, vector = _as_coeffs(coeffs)
    e = np.moveaxis(e, -2, -1)  # (..., C, 9)
    lifted = np.einsum("...i,ijk->...jk", e, LIFT_MAP)
    c, g, a = lifted[..., 0, 0], 2.0 * lifted[..., 0, 1:], lifted[..., 1:, 1:]
    return (c[..., 0], g[..., 0, :], a[..., 0, :, :]) if vector else (c, g, a)


def lifted_matrix(coeffs: ArrayLike, mu: ArrayLike, margin: float = 0.0) -> NDArray[np.float64]:
    """
    The certificate matrix M(mu) - margin x mean(f) e_0 e_0^T (module docstring).

    Parameters
    ----------
    coeffs
        (9,) or (..., 9, C) 3-band coefficients.
    mu
        Multiplier, broadcasting with (..., C) (or scalar for (9,) input).
    margin
        Required minimum as a fraction of the function's mean Y00 e0 (0 for f >= 0).

    Returns
    -------
    ndarray
        (..., C, 4, 4), or (4, 4) for (9,) input; rows and columns ordered (1, x, y, z).
        PSD for some mu iff f >= margin x mean on the sphere.
    """
    e, vector = _as_coeffs(coeffs)
    e = np.moveaxis(e, -2, -1)
    m = np.einsum("...i,ijk->...jk", e, LIFT_MAP) + np.asarray(mu, dtype=np.float64)[..., None, None] * MU_MATRIX
    m[..., 0, 0] -= margin * Y00 * e[..., 0]
    return m[..., 0, :, :] if vector else m


def sphere_minimum(coeffs: ArrayLike, return_dirs: bool = False) -> Any:
    """
    Exact minimum of 3-band SH functions over the unit sphere (the dual of the module docstring).

    Parameters
    ----------
    coeffs
        (9,) or (..., 9, C) coefficients.
    return_dirs
        Also return a unit vector where the minimum is attained.

    Returns
    -------
    minimum : ndarray or float
        (..., C) (a float for (9,) input), in the coefficients' unit: max_mu d(mu),
        a lower bound at every bisection step (weak duality) that equals the
        minimum to rounding once converged (:data:`_BISECTION_STEPS`).
    dirs : ndarray
        (..., C, 3) argmin directions (f there exceeds the minimum by rounding only),
        if ``return_dirs``.

    Notes
    -----
    A = Q diag(lambda) Q^T (lambda ascending), h = Q^T g. The root mu* < lambda_1 of
    phi(mu) = sum h_i^2 / (4 (lambda_i - mu)^2) = 1 lies in [lambda_1 - |g| / 2, lambda_1]
    (phi <= 1 at the left end); bisection keeps phi(lo) <= 1, where the concave
    d(lo) is a lower bound. Each function is scaled by its largest coefficient first,
    so no sum overflows. Vectorised, deterministic, no Python loop over functions.
    """
    e, vector = _as_coeffs(coeffs)
    scale = np.max(np.abs(e), axis=-2, keepdims=True)
    scale = np.where(scale > 0.0, scale, 1.0)
    c, g, a = quadratic_parts(e / scale)
    lam, q = np.linalg.eigh(a)
    h = np.einsum("...ji,...j->...i", q, g)
    h2 = h * h
    lo = lam[..., 0] - 0.5 * np.sqrt(np.sum(h2, axis=-1))
    hi = lam[..., 0].copy()
    for _ in range(_BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        gap = lam - mid[..., None]
        with np.errstate(divide="ignore", invalid="ignore"):
            phi = np.sum(np.where(h2 > 0.0, h2 / (4.0 * gap * gap), 0.0), axis=-1)
        inside = phi <= 1.0
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    gap = lam - lo[..., None]
    # gap = 0 with h != 0 only when |g| / 2 is below the float spacing of lambda_1: the
    # term is then below rounding (<= |g|) and is dropped, as in the hard case.
    valid = (h2 > 0.0) & (gap > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(valid, h2 / (4.0 * gap), 0.0)
        y = np.where(valid, -h / (2.0 * gap), 0.0)  # w(mu) in the eigenbasis
    minimum = (c + lo - np.sum(terms, axis=-1)) * scale[..., 0, :]
    if vector:
        minimum = minimum[..., 0]
    if not return_dirs:
        return float(minimum) if vector else minimum
    # Hard case (|w| < 1 at the converged mu): complete along the smallest eigenvector.
    missing = np.sqrt(np.maximum(0.0, 1.0 - np.sum(y * y, axis=-1)))
    y[..., 0] += np.copysign(missing, y[..., 0])
    w = np.einsum("...ij,...j->...i", q, y)
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    return (float(minimum), w[..., 0, :]) if vector else (minimum, w)


def radiance_equivalent(coeffs: ArrayLike) -> NDArray[np.float64]:
    """Irradiance coefficients (..., 9, C) divided by A_l: the radiance whose irradiance they are."""
    e, vector = _as_coeffs(coeffs)
    out = e / LOBE[:, None]
    return out[..., 0] if vector else out


# --------------------------------------------------------------------------- #
# The truth and the normals
# --------------------------------------------------------------------------- #
def true_irradiance(
    sun_zenith: float,
    turbidity: float,
    bands: int = TRUTH_BANDS,
    n_theta: int | None = TRUTH_THETA_NODES,
    colourspace: str = "sRGB",
) -> NDArray[np.float64]:
    """
    Irradiance SH of the true sky, sun at azimuth 0: A_l times :func:`skysh.preetham.sky_sh`.

    Parameters
    ----------
    sun_zenith, turbidity
        Radians in [0, pi/2]; turbidity in [1.7, 10] (the model's domain).
    bands
        Bands of the projection, [3, 64].
    n_theta
        Zenith nodes per panel of :func:`skysh.preetham.sky_quadrature_rule`
        (None: the projection's default, 64).
    colourspace
        colour-science RGB colourspace name.

    Returns
    -------
    ndarray
        (bands^2, 3) irradiance coefficients, cd/m^2 x sr; the m < 0 rows are zero.
    """
    bands = check_bands(bands, high=sh.MAX_BANDS)
    if bands < 3:
        raise ValueError(f"bands must be an integer in [3, {sh.MAX_BANDS}], got {bands}")
    n = None if n_theta is None else 4 * int(n_theta) ** 2
    return sh.irradiance(preetham.sky_sh(sun_zenith, turbidity, bands, colourspace=colourspace, n=n))


def _fibonacci_sphere(count: int) -> NDArray[np.float64]:
    """``count`` points of the Fibonacci (golden-angle) spiral on the unit sphere, z descending."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = i * (math.pi * (3.0 - math.sqrt(5.0)))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def half_sphere_normals(count: int = OPTIMISATION_NORMALS) -> NDArray[np.float64]:
    """
    The y >= 0 half of a ``count``-point Fibonacci sphere, plus the zenith and the nadir.

    A function symmetric in y -> -y (the sky with its sun at azimuth 0, and the
    solutions sought) takes all its values there. Returns (M, 3) unit vectors,
    M about count / 2 + 2. ``count`` in [16, 10^6].
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 16 <= count <= 10**6:
        raise ValueError(f"count must be an integer in [16, 1000000], got {count!r}")
    points = _fibonacci_sphere(int(count))
    return np.concatenate([points[points[:, 1] >= 0.0], [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])


# --------------------------------------------------------------------------- #
# The convex problems
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class Objective:
    """
    What :func:`constrained_coefficients` optimises (hashable: one compiled problem each).

    Attributes
    ----------
    method
        One of :data:`METHODS`.
    margin
        Required minimum f >= margin x mean(f), a fraction in [0, 0.5] (ignored by
        ``"minimax_free"``).
    weight
        Weight of the squared relative RMS error in ``"blend"``, [0, 1e6].
    chroma
        None, or the largest CIE 1976 u'v' distance to the truth allowed at every
        optimisation normal lit at least :data:`CHROMA_FLOOR` x the mean
        luminance irradiance, (0, 1]: an exact second-order cone per normal that
        couples the channels (module docstring, "Colour").
    normals
        Fibonacci-sphere size of the worst-case objectives (:func:`half_sphere_normals`).
    """

    method: str = "l2"
    margin: float = 0.0
    weight: float = BLEND_WEIGHT
    chroma: float | None = None
    normals: int = OPTIMISATION_NORMALS

    def __post_init__(self) -> None:
        check_choice(self.method, "method", METHODS)
        object.__setattr__(self, "margin", float(check_range(self.margin, "margin", 0.0, 0.5)))
        object.__setattr__(self, "weight", float(check_range(self.weight, "weight", 0.0, 1e6)))
        if self.chroma is not None:
            object.__setattr__(self, "chroma", float(check_range(self.chroma, "chroma", 1e-6, 1.0)))
        half_sphere_normals(self.normals)  # validates the count

    @property
    def needs_normals(self) -> bool:
        """Whether the truth beyond 3 bands enters (worst-case objectives or the colour constraint)."""
        return self.method != "l2" or self.chroma is not None


RECOMMENDED: Objective = Objective("blend", margin=1e-3, weight=100.0, chroma=0.01)
"""The objective the study chose for the shipped table (``tools/irradiance_study.py``
prints why): worst error + 100 x RMS^2, u'v' <= 0.01 at lit normals, f >= 0.1% of the mean."""

_PROBLEMS: dict[Objective, Any] = {}
"""Per process: the cvxpy problem of each :class:`Objective`, built once (parameters
change per solve: cvxpy's DPP reuses the compiled problem)."""


def _build_problem(obj: Objective) -> Any:
    """The cvxpy problem of the three channels, each scaled so its true mean irradiance is 1."""
    import cvxpy as cp  # the tools extra; never imported by the runtime

    normals = half_sphere_normals(obj.normals)
    basis = sh.basis(normals, 3)[:, HALF_ROWS]  # (M, 6)
    x, mu = cp.Variable((len(HALF_ROWS), 3)), cp.Variable(3)
    target, values = cp.Parameter((len(HALF_ROWS), 3)), cp.Parameter((normals.shape[0], 3))
    shift = np.zeros((4, 4))
    shift[0, 0] = obj.margin * Y00
    constraints = []
    for ch in range(3 if obj.method != "minimax_free" else 0):
        lifted = sum(x[k, ch] * LIFT_MAP[row] for k, row in enumerate(HALF_ROWS)) + mu[ch] * MU_MATRIX
        constraints.append(lifted - x[0, ch] * shift >> 0)
    residual = basis @ x - values
    if obj.method == "l2":
        objective = cp.sum_squares(x - target)
    elif obj.method == "lp":
        objective = sum(cp.pnorm(residual[:, ch], LP_EXPONENT) for ch in range(3))
    else:
        bound = cp.Variable(3)
        constraints += [residual <= cp.reshape(bound, (1, 3), order="C"), -residual <= cp.reshape(bound, (1, 3), order="C")]
        objective = cp.sum(bound)
        if obj.method == "blend":  # relative RMS^2 = |x - target|^2 / (4 pi) up to the constant band-limit tail
            objective = objective + (obj.weight / (4.0 * math.pi)) * cp.sum_squares(x - target)
    colour = None
    if obj.chroma is not None:  # rows (u', v', D) of XYZ times the truth's (u', v') and the channel means
        colour = [cp.Parameter((normals.shape[0], 3)) for _ in range(3)]
        u, v, d = (sum(cp.multiply(p[:, ch], basis @ x[:, ch]) for ch in range(3)) for p in colour)
        constraints.append(cp.SOC(obj.chroma * d, cp.vstack([u, v]), axis=0))
    problem = cp.Problem(cp.Minimize(objective), constraints)
    return problem, x, target, values, colour, normals


def _problem(obj: Objective) -> Any:
    if obj not in _PROBLEMS:
        _PROBLEMS[obj] = _build_problem(obj)
    return _PROBLEMS[obj]


@lru_cache(maxsize=4)
def _normal_basis(count: int, bands: int) -> NDArray[np.float64]:
    """The basis (M, bands^2) at :func:`half_sphere_normals` (count), read-only (67 MB at 64 bands)."""
    basis = sh.basis(half_sphere_normals(count), bands)
    basis.flags.writeable = False
    return basis


def _colour_rows(true_values: NDArray, mean: NDArray, colourspace: str) -> list[NDArray]:
    """Parameters of the u'v' cones: (M, 3) rows mapping scaled RGB to (4X - u'D, 9Y - v'D, D); unlit normals 0."""
    xyz_from_rgb = np.linalg.inv(preetham.rgb_from_xyz_matrix(colourspace))
    xyz = true_values @ xyz_from_rgb.T
    d_row = xyz_from_rgb[0] + 15.0 * xyz_from_rgb[1] + 3.0 * xyz_from_rgb[2]
    denominator = xyz @ np.array([1.0, 15.0, 3.0])
    lit = xyz[:, 1] >= CHROMA_FLOOR * float(mean @ xyz_from_rgb[1])
    safe = np.where(denominator > 0.0, denominator, 1.0)
    u, v = 4.0 * xyz[:, 0] / safe, 9.0 * xyz[:, 1] / safe
    rows = [4.0 * xyz_from_rgb[0] - u[:, None] * d_row, 9.0 * xyz_from_rgb[1] - v[:, None] * d_row,
            np.broadcast_to(d_row, u.shape + (3,))]
    return [np.where(lit[:, None], r, 0.0) * mean for r in rows]


def constrained_coefficients(
    truth: ArrayLike, objective: Objective = Objective(), colourspace: str = "sRGB"
) -> tuple[NDArray[np.float64], dict[str, Any]]:
    """
    One sky's optimal 3-band irradiance subject to f >= margin x mean(f) in every channel.

    Parameters
    ----------
    truth
        (K, 3) true irradiance SH of a sky with its sun at azimuth 0 (K = N^2 >= 9;
        :func:`true_irradiance`); the L2 objective uses its first 9 rows, the
        worst-case objectives and the colour constraint the whole series at the
        normals of :func:`half_sphere_normals`.
    objective
        :class:`Objective`.
    colourspace
        The truth's RGB space (for the colour constraint's XYZ).

    Returns
    -------
    coeffs, info
        (9, 3) irradiance coefficients (m < 0 rows zero), and ``objective`` the
        optimal value (on the problem scaled so each true mean is 1), ``minimum``
        (3,) the exact minimum over the sphere relative to the function's mean
        (:func:`sphere_minimum`), ``repair`` (3,) the solver's feasibility
        shortfall made good (:func:`_repair`), ``status``.

    Raises
    ------
    RuntimeError
        If the solver does not report an optimal solution.
    """
    t = as_float_array(truth, "truth")
    if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] < 9 or math.isqrt(t.shape[0]) ** 2 != t.shape[0]:
        raise ValueError(f"truth must have shape (N*N, 3) with N >= 3, got {t.shape}")
    mean = Y00 * t[0]
    if not np.all(mean > 0.0):
        raise ValueError(f"truth must have a positive mean irradiance in every channel, got {t[0]}")
    problem, x, target, values, colour, _ = _problem(objective)
    bands = math.isqrt(t.shape[0])
    true_values = _normal_basis(objective.normals, bands) @ t if objective.needs_normals else np.zeros(values.shape)
    target.value = t[list(HALF_ROWS)] / mean
    values.value = true_values / mean
    if colour is not None:
        for parameter, rows in zip(colour, _colour_rows(true_values, mean, colourspace)):
            parameter.value = rows
    problem.solve(solver="CLARABEL", **_SOLVER_OPTIONS)
    if problem.status != "optimal" or x.value is None:
        raise RuntimeError(f"the {objective} problem ended with status {problem.status!r}")
    out = np.zeros((9, 3))
    out[list(HALF_ROWS)] = x.value * mean
    info: dict[str, Any] = {"objective": float(problem.value), "status": problem.status}
    info["repair"] = _repair(out, objective.margin) if objective.method != "minimax_free" else np.zeros(3)
    info["minimum"] = sphere_minimum(out) / (Y00 * out[0])
    return out, info


def _repair(coeffs: NDArray, margin: float) -> NDArray:
    """Raise e0 (in place) by the solver's feasibility shortfall so f >= margin x mean holds exactly.

    f + Y00 d against a requirement raised by margin Y00 d: d = shortfall / (Y00 (1 - margin)),
    plus 16 eps of e0 for the rounding of the exact minimum. Returns the shortfall / mean (3,).
    """
    shortfall = np.maximum(0.0, margin * Y00 * coeffs[0] - sphere_minimum(coeffs)) / (Y00 * coeffs[0])
    if np.any(shortfall > _REPAIR_LIMIT):
        raise RuntimeError(f"the solution misses the constraint by {shortfall} of the mean (solver failure)")
    coeffs[0] *= np.where(shortfall > 0.0, 1.0 + shortfall / (1.0 - margin) + 16.0 * np.finfo(float).eps, 1.0)
    return shortfall


def constrained_point(job: tuple[float, float, Objective]) -> tuple[NDArray[np.float64], dict[str, Any]]:
    """
    :func:`constrained_coefficients` at one (sun_zenith, turbidity, objective); top level, so process pools can pickle it.

    The truth is :func:`true_irradiance` at :data:`TRUTH_BANDS` when the objective
    needs normals, else 3 bands at the projection's default nodes (all L2 needs).
    """
    sun_zenith, turbidity, objective = job
    if objective.needs_normals:
        truth = true_irradiance(sun_zenith, turbidity)
    else:
        truth = true_irradiance(sun_zenith, turbidity, 3, None)
    return constrained_coefficients(truth, objective)


def constrained_irradiance_grid(
    sun_zenith: ArrayLike,
    turbidity: ArrayLike,
    objective: Objective = RECOMMENDED,
    mapper: Callable[[Callable, Iterable], Iterable] = map,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    The constrained optimum over the product grid of ``sun_zenith`` x ``turbidity``.

    Parameters
    ----------
    sun_zenith
        (n_ts,) radians in [0, pi/2].
    turbidity
        (n_t,) in [1.7, 10].
    objective
        :class:`Objective`; default :data:`RECOMMENDED`.
    mapper
        ``map``-like callable (e.g. a process pool's ``map``); results must come
        back in order. Same inputs, same output (Clarabel is deterministic).

    Returns
    -------
    coeffs, minimum
        (n_ts, n_t, 9, 3) **irradiance** coefficients (cd/m^2 x sr, linear sRGB,
        sun at azimuth 0, m < 0 rows zero; :func:`radiance_equivalent` for the
        radiance form), and (n_ts, n_t, 3) their exact minima relative to the mean.
    """
    ts = check_range(np.atleast_1d(sun_zenith), "sun_zenith", *preetham.SUN_ZENITH_RANGE, unit="rad")
    tu = check_range(np.atleast_1d(turbidity), "turbidity", *preetham.TURBIDITY_RANGE)
    if ts.ndim != 1 or tu.ndim != 1:
        raise ValueError(f"sun_zenith and turbidity must be 1-D, got shapes {ts.shape} and {tu.shape}")
    if not isinstance(objective, Objective):
        raise TypeError(f"objective must be an irradiance_fit.Objective, got {objective!r}")
    results = list(mapper(constrained_point, [(float(a), float(b), objective) for a in ts for b in tu]))
    coeffs = np.stack([r[0] for r in results]).reshape(ts.size, tu.size, 9, 3)
    minimum = np.stack([r[1]["minimum"] for r in results]).reshape(ts.size, tu.size, 3)
    return coeffs, minimum


# --------------------------------------------------------------------------- #
# The table
# --------------------------------------------------------------------------- #
def fit_irradiance_table(
    sun_zenith: ArrayLike, turbidity: ArrayLike, coeffs: ArrayLike, degrees: tuple[int, int] = (13, 7)
) -> tuple[NDArray[np.float64], NDArray[np.int64], float]:
    """
    Fit irradiance coefficients at points with the sky table's polynomial (:func:`skysh.fit.fit_table`).

    Parameters
    ----------
    sun_zenith, turbidity
        (P,) points (radians; turbidity).
    coeffs
        (P, 9, 3) irradiance coefficients at the points (m < 0 rows ignored: zero).
    degrees
        (d_theta, d_tau) for every band.

    Returns
    -------
    table, degrees, condition
        (n_terms, 6, 3) Chebyshev coefficients of the **radiance-equivalent**
        m >= 0 rows divided by the luminance scale (the sky table's exact form:
        the runtime multiplies by A_l as for the sky), the (3, 2) degrees, and
        the largest condition number solved. Residuals are weighted by the
        inverse of each point's mean irradiance per channel.
    """
    e = as_float_array(coeffs, "coeffs")
    if e.ndim != 3 or e.shape[1:] != (9, 3):
        raise ValueError(f"coeffs must have shape (P, 9, 3), got {e.shape}")
    half = radiance_equivalent(e)[:, list(HALF_ROWS)]
    per_band = np.tile(np.asarray(degrees, dtype=np.int64), (3, 1))
    table, condition = fit.fit_table(np.asarray(sun_zenith), np.asarray(turbidity), half, Y00 * e[:, 0], per_band)
    return table, per_band, condition


def evaluate_irradiance_table(
    table: NDArray, degrees: NDArray, sun_zenith: ArrayLike, turbidity: ArrayLike
) -> NDArray[np.float64]:
    """The tabulated irradiance at (P,) points: (P, 9, 3) coefficients, sun at azimuth 0 (m < 0 rows zero)."""
    half = fit.evaluate_table(table, degrees, np.asarray(sun_zenith), np.asarray(turbidity))
    out = np.zeros((half.shape[0], 9, 3))
    out[:, list(HALF_ROWS)] = half
    return out * LOBE[:, None]
