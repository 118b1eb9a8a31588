"""
Offline: the best non-negative 3-band irradiance of the sky (issue 18)
======================================================================

Per (sun zenith, turbidity), the 3-band irradiance coefficients that are closest
to the true sky irradiance (in L2 or in the worst case over normals) subject to
being **non-negative on the whole sphere**, certified by a 4x4 matrix inequality
(below). An offline module for ``tools/irradiance_study.py`` and the fit tool:
the runtime never imports it, and cvxpy (the ``tools`` extra; solver Clarabel)
is imported inside the functions that solve. :func:`solver_available` says whether
they can run here; without the solver they raise ModuleNotFoundError naming the
package, the extra and :data:`SOLVER_INSTALL` (:func:`solver_missing_message`).

-   :func:`quadratic_parts`: (c, g, A) of f(w) = c + g.w + w^T A w from 9 SH coefficients.
-   :func:`lifted_matrix`: the 4x4 matrix M(mu) whose PSD-ness certifies f >= 0.
-   :func:`sphere_minimum`: the minimum of a 3-band function on the sphere (never above it; :mod:`skysh.sh.minimum`).
-   :func:`true_irradiance`: the sky's converged irradiance coefficients (many bands).
-   :func:`half_sphere_normals`: the normals the worst-case objectives are taken over.
-   :func:`constrained_coefficients`: one sky's constrained optimum, every channel.
-   :func:`constrained_point`: the same from (sun zenith, turbidity); process-pool friendly.
-   :func:`constrained_irradiance_grid`: the optimum over a (sun zenith, turbidity) grid.
-   :func:`fit_irradiance_table`, :func:`evaluate_irradiance_table`: the optimum as a
    Chebyshev table in the sky table's form (:mod:`skysh.table.fit`).
-   :func:`build_table`: the coefficient file's irradiance table, measured and certified.
-   :func:`solver_available`, :func:`require_solver`: whether the solver (the tools extra) is installed; one clear
    ModuleNotFoundError if not.

Coefficients are **irradiance** SH (E(l, m) = A_l L(l, m), cd/m^2 x sr, linear RGB)
in the layout of ``docs/conventions.md`` (real, orthonormal, Condon-Shortley phase,
index l (l + 1) + m), shaped (9, 3); :func:`radiance_equivalent` divides by A_l.

The certificate (S-lemma for one quadratic equality; derivation: ``docs/irradiance.md``)
--------------------------------------------------------------------------------------
A 3-band function is f(w) = c + g.w + w^T A w on the sphere (:func:`quadratic_parts`, from
:data:`skysh.sh.minimum.FORM_MAP`: the closed forms of the convention's table, with the
Condon-Shortley minus signs, A traceless; any multiple of (1 - |w|^2) may be moved between
c and A, and is absorbed by mu below). For any
real mu and |w| = 1, f(w) = (1, w) M(mu) (1, w)^T with ``M(mu) = [[c + mu, g^T / 2],
[g / 2, A - mu I]]`` (:func:`lifted_matrix`): M(mu) PSD for some mu => f >= 0, and
conversely (no duality gap for one quadratic equality: More and Sorensen 1983; Stern and
Wolkowicz 1995; Polik and Terlaky 2007), so "f >= 0 on the sphere" is exactly a 4 x 4
linear matrix inequality in the coefficients: exact, not a relaxation. A margin s
(f >= s) is the same for M(mu) - s e_0 e_0^T; :func:`constrained_coefficients` uses
s = margin x mean(f), mean(f) = Y00 e0, linear in the unknowns. :func:`sphere_minimum`
evaluates the dual max_mu d(mu) = min_sphere f (:func:`skysh.sh.minimum.exact_min`, never above it).

Colour and symmetry (derivations: ``docs/irradiance.md``)
--------------------------------------------------------
"CIE 1976 u'v' distance to the truth <= eps" at a normal is exactly a second-order cone,
linear in the three channels together (:attr:`Objective.chroma`). With the sun at azimuth 0
the problems are symmetric in y -> -y and convex, so the m < 0 coefficients are zero at an
optimum: 6 unknowns per channel, the rows of :data:`HALF_ROWS`.

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

import importlib.util
import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from functools import cache, lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_bands, check_choice, check_coeffs, check_count, check_range
from skysh.model import preetham
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin
from skysh.table import fit

__all__ = ["Y00", "RECOMMENDED", "sphere_minimum", "constrained_coefficients", "FIT_ERROR_POINTS", "build_table",
    "solver_available", "solver_missing_message"]

# --------------------------------------------------------------------------- #
# The solver: the tools extra, imported only by the functions that solve
# --------------------------------------------------------------------------- #
SOLVER_PACKAGES: tuple[str, ...] = ("cvxpy", "clarabel")
"""Import names of what the solves need: cvxpy (the problems) and Clarabel (its solver, ``solver="CLARABEL"``)."""

SOLVER_EXTRA: str = "tools"
"""The optional dependencies (``pyproject.toml``) that bring :data:`SOLVER_PACKAGES`."""

SOLVER_INSTALL: str = f'pip install -e ".[{SOLVER_EXTRA}]"'
"""The command that installs :data:`SOLVER_EXTRA` in a source checkout (where the tools that solve live)."""

_SOLVES: str = "solving skysh.table.irradiance_fit's convex problems"
"""What needs the solver, in the messages of the functions that solve."""


def missing_solver_packages() -> tuple[str, ...]:
    """The packages of :data:`SOLVER_PACKAGES` that cannot be found here (none: the solves can run).

    Looks them up without importing them (``importlib.util.find_spec``: cheap, cvxpy's import is not).
    """
    return tuple(name for name in SOLVER_PACKAGES if importlib.util.find_spec(name) is None)


def solver_available() -> bool:
    """Whether the convex solves can run here (every package of :data:`SOLVER_PACKAGES` is installed)."""
    return not missing_solver_packages()


def solver_missing_message(task: str = _SOLVES) -> str:
    """One line: ``task`` needs the missing solver packages, their extra and the command that installs it."""
    missing = missing_solver_packages() or SOLVER_PACKAGES[:1]
    verb = "is" if len(missing) == 1 else "are"
    return f"{task} needs {' and '.join(missing)} (the {SOLVER_EXTRA} extra), which {verb} not installed: {SOLVER_INSTALL}"


def require_solver(task: str = _SOLVES) -> None:
    """
    Refuse before any work when the solver is missing.

    Raises
    ------
    ModuleNotFoundError
        :func:`solver_missing_message` of ``task``; ``name`` is the first missing package.
    """
    missing = missing_solver_packages()
    if missing:
        raise ModuleNotFoundError(solver_missing_message(task), name=missing[0])


Y00: float = sh.Y00
"""Y(0, 0) = 1 / (2 sqrt(pi)) (:data:`skysh.sh.basis.Y00`); the mean of a function over the sphere is Y00 e0."""

LOBE: NDArray[np.float64] = sh.cosine_lobe(3)[np.repeat(np.arange(3), 2 * np.arange(3) + 1)]
"""(9,) clamped-cosine factor A_l of every 3-band coefficient (pi, 2 pi / 3 x 3, pi / 4 x 5)."""
LOBE.flags.writeable = False

HALF_ROWS: tuple[int, ...] = (0, 2, 3, 6, 7, 8)
"""Flat indices of the m >= 0 coefficients (0,0), (1,0), (1,1), (2,0), (2,1), (2,2):
the layout of :func:`skysh.table.coefficient_file.zonal_half_layout` (3)."""


def _lift_map() -> NDArray[np.float64]:
    """(9, 4, 4): M(mu) = sum_i e_i LIFT_MAP[i] + mu MU_MATRIX, rows/columns ordered (1, x, y, z): row i of
    :data:`skysh.sh.minimum.FORM_MAP` (c_i, g_i, Q_i) as [[c_i, g_i^T / 2], [g_i / 2, Q_i]]."""
    form = shmin.FORM_MAP
    m = np.zeros((9, 4, 4))
    m[:, 0, 0] = form[:, 0]
    m[:, 0, 1:] = m[:, 1:, 0] = 0.5 * form[:, 1:4]
    m[:, 1:, 1:] = form[:, 4:].reshape(9, 3, 3)
    m.flags.writeable = False
    return m


LIFT_MAP: NDArray[np.float64] = _lift_map()
"""(9, 4, 4) constant matrices: f(w) = (1, w) [sum_i e_i LIFT_MAP[i]] (1, w)^T for every w."""

MU_MATRIX: NDArray[np.float64] = np.diag([1.0, -1.0, -1.0, -1.0])
"""The multiplier's matrix in M(mu): mu (1 - |w|^2) = (1, w) MU_MATRIX (1, w)^T * mu."""
MU_MATRIX.flags.writeable = False

METHODS: tuple[str, ...] = ("l2", "minimax", "minimax_free", "lp", "blend")
"""Objectives: ``"l2"`` closest in L2 (coefficient distance; Parseval) subject to f >= margin x
mean; ``"minimax"`` smallest worst error over the normals subject to the same; ``"minimax_free"``
the same unconstrained (the floor of three bands); ``"lp"`` the L_p norm (p = :data:`LP_EXPONENT`)
of the error over the normals, constrained; ``"blend"`` the worst error plus ``weight`` times the
squared relative RMS error (Parseval), constrained: strictly convex, a unique optimum."""

BLEND_WEIGHT: float = 1.0
"""Default weight of the squared relative RMS error in the ``"blend"`` objective."""

TRUTH_BANDS: int = 32
"""Bands of the true irradiance the worst-case objectives are taken against: its tail leaves
at most about 5e-4 of the mean irradiance against 64 bands, next to the nadir
(``tools/irradiance_study.py`` prints the convergence table), far below a worst error of percents."""

TRUTH_THETA_NODES: int = 40
"""Zenith nodes per panel of the sky quadrature for :data:`TRUTH_BANDS` bands: within
about 1e-7 of the mean irradiance of the default 64 nodes at 32 bands (printed by the
study), at a third of the cost."""

OPTIMISATION_NORMALS: int = 4096
"""Fibonacci-sphere size whose y >= 0 half (plus the poles) carries the worst-case objectives and
the colour constraint: about 2,050 normals, 3.2 degrees apart (the study measures on 12,168 others)."""

CHROMA_FLOOR: float = 0.05
"""The colour constraint applies where the true luminance irradiance is at least this fraction of
its mean: below it (next to the nadir) the chromaticity of a twentieth of the light is ill-conditioned."""

LP_EXPONENT: int = 8
"""Exponent p of the ``"lp"`` blend: large enough to weigh the worst normals, small
enough to stay smooth in the sky's parameters."""

_SOLVER_OPTIONS: dict[str, Any] = {}
"""Clarabel's defaults (tolerances 1e-8 on the problem scaled so the true mean irradiance is 1), far
below every figure the study prints; 1e-9 ends "optimal_inaccurate" on some worst-case problems."""

_REPAIR_LIMIT: float = 1e-6
"""Largest constraint shortfall (of the mean) that :func:`constrained_coefficients`
repairs by raising e0; a larger one is a solver failure (RuntimeError)."""


# --------------------------------------------------------------------------- #
# The quadratic form, the certificate and the exact minimum
# --------------------------------------------------------------------------- #
def _as_coeffs(coeffs: ArrayLike, name: str = "coeffs") -> tuple[NDArray[np.float64], bool]:
    """(..., 9, C) float array from (9,), (9, C) or (..., 9, C); flag whether the input was (9,)."""
    c, vector, _ = check_coeffs(coeffs, name, high=3, low=3)
    return c, vector


def quadratic_parts(coeffs: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    """
    The polynomial form f(w) = c + g.w + w^T A w of 3-band SH on the unit sphere.

    ``coeffs`` (9,) or (..., 9, C), any unit. Returns c, g, A of shapes (..., C), (..., C, 3) and
    (..., C, 3, 3) (without the C axis for (9,) input): :func:`skysh.sh.minimum.sphere_quadratic`
    (A symmetric and traceless) with the coefficient axis second to last, as everywhere here.
    """
    e, vector = _as_coeffs(coeffs)
    c, g, a = shmin.sphere_quadratic(np.moveaxis(e, -2, -1))  # (..., C, 9) -> (..., C), (..., C, 3), (..., C, 3, 3)
    return (c[..., 0], g[..., 0, :], a[..., 0, :, :]) if vector else (c, g, a)


def lifted_matrix(coeffs: ArrayLike, mu: ArrayLike, margin: float = 0.0) -> NDArray[np.float64]:
    """
    The certificate matrix M(mu) - margin x mean(f) e_0 e_0^T (module docstring).

    ``coeffs`` (9,) or (..., 9, C); ``mu`` the multiplier, broadcasting with (..., C); ``margin``
    the required minimum as a fraction of the mean Y00 e0. Returns (..., C, 4, 4) ((4, 4) for
    (9,) input), rows and columns (1, x, y, z): PSD for some mu iff f >= margin x mean.
    """
    e, vector = _as_coeffs(coeffs)
    e = np.moveaxis(e, -2, -1)
    m = np.einsum("...i,ijk->...jk", e, LIFT_MAP) + np.asarray(mu, dtype=np.float64)[..., None, None] * MU_MATRIX
    m[..., 0, 0] -= margin * Y00 * e[..., 0]
    return m[..., 0, :, :] if vector else m


def sphere_minimum(coeffs: ArrayLike, return_dirs: bool = False) -> Any:
    """
    Minimum of 3-band SH functions over the unit sphere, never above the true one.

    ``coeffs``: (9,) or (..., 9, C). Returns the minimum, (..., C) (a float for (9,) input), in
    the coefficients' unit, and with ``return_dirs`` (..., C, 3) unit directions where it is
    attained (to rounding): :func:`skysh.sh.minimum.exact_min` restricted to 3 bands, the dual
    max_mu d(mu) of the module docstring at its root (Newton's method from a proven bound),
    less a rounding allowance (2.3e-13 of the largest |coefficient|, rounded up to a power
    of 2), so a value >= 0 certifies f >= 0.
    """
    _as_coeffs(coeffs)  # 3 bands only: the S-lemma certificate of this module
    return shmin.exact_min(coeffs, return_dirs)


def radiance_equivalent(coeffs: ArrayLike) -> NDArray[np.float64]:
    """Irradiance coefficients (..., 9, C) divided by A_l: the radiance whose irradiance they are."""
    e, vector = _as_coeffs(coeffs)
    out = e / LOBE[:, None]
    return out[..., 0] if vector else out


# --------------------------------------------------------------------------- #
# The truth and the normals
# --------------------------------------------------------------------------- #
def true_irradiance(sun_zenith: float, turbidity: float, bands: int = TRUTH_BANDS, n_theta: int | None = TRUTH_THETA_NODES,
                    colourspace: str = "sRGB") -> NDArray[np.float64]:
    """
    Irradiance SH of the true sky, sun at azimuth 0: A_l times :func:`skysh.model.preetham.sky_sh`.

    Parameters
    ----------
    sun_zenith, turbidity
        Radians in [0, pi/2]; turbidity in [1.7, 10] (the model's domain).
    bands
        Bands of the projection, [3, 64].
    n_theta
        Zenith nodes per panel of :func:`skysh.model.preetham.sky_quadrature_rule`
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


def half_sphere_normals(count: int = OPTIMISATION_NORMALS) -> NDArray[np.float64]:
    """
    The y >= 0 half of a ``count``-point Fibonacci sphere, plus the zenith and the nadir.

    A function symmetric in y -> -y (the sky with its sun at azimuth 0, and the
    solutions sought) takes all its values there. Returns (M, 3) unit vectors,
    M about count / 2 + 2. ``count`` in [16, 10^6].
    """
    count = check_count(count, "count", 16, 10**6)
    points = shmin.fibonacci(int(count))
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

@cache
def _problem(obj: Objective) -> Any:
    """The cvxpy problem of the three channels, each scaled so its true mean irradiance is 1.

    Built once per process and :class:`Objective` (parameters change per solve: cvxpy's DPP reuses the compiled problem).
    """
    require_solver()  # one clear line naming the extra, not cvxpy's bare "No module named"
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


def constrained_coefficients(truth: ArrayLike, objective: Objective = Objective(),
                             colourspace: str = "sRGB") -> tuple[NDArray[np.float64], dict[str, Any]]:
    """
    One sky's optimal 3-band irradiance subject to f >= margin x mean(f) in every channel.

    ``truth``: (K, 3) true irradiance SH of a sky with its sun at azimuth 0 (K = N^2 >= 9;
    :func:`true_irradiance`); L2 uses its first 9 rows, the worst-case objectives and the colour
    constraint the whole series at :func:`half_sphere_normals`. ``objective``: :class:`Objective`.
    ``colourspace``: the truth's RGB space (for the colour constraint's XYZ).

    Returns (9, 3) irradiance coefficients (m < 0 rows zero) and ``info``: ``objective`` the
    optimal value (problem scaled so each true mean is 1), ``minimum`` (3,) the exact minimum
    relative to the mean (:func:`sphere_minimum`), ``repair`` (3,) the feasibility shortfall
    made good (:func:`_repair`), ``status``. RuntimeError if the solver does not end optimal.
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


def constrained_point(job: tuple) -> tuple[NDArray[np.float64], dict[str, Any]]:
    """
    :func:`constrained_coefficients` at one (sun_zenith, turbidity, objective[, colourspace]); top level, so
    process pools can pickle it (colourspace default sRGB).

    The truth is :func:`true_irradiance` at :data:`TRUTH_BANDS` when the objective
    needs normals, else 3 bands at the projection's default nodes (all L2 needs).
    """
    sun_zenith, turbidity, objective, colourspace = (*job, "sRGB")[:4]
    bands, nodes = (TRUTH_BANDS, TRUTH_THETA_NODES) if objective.needs_normals else (3, None)
    truth = true_irradiance(sun_zenith, turbidity, bands, nodes, colourspace)
    return constrained_coefficients(truth, objective, colourspace)


def constrained_irradiance_grid(sun_zenith: ArrayLike, turbidity: ArrayLike, objective: Objective = RECOMMENDED,
                                mapper: Callable[[Callable, Iterable], Iterable] = map,
                                colourspace: str = "sRGB") -> tuple[NDArray[np.float64], NDArray[np.float64]]:
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
    colourspace
        colour-science RGB colourspace of the truth and of the result.

    Returns
    -------
    coeffs, minimum
        (n_ts, n_t, 9, 3) **irradiance** coefficients (cd/m^2 x sr, linear RGB,
        sun at azimuth 0, m < 0 rows zero; :func:`radiance_equivalent` for the
        radiance form), and (n_ts, n_t, 3) their exact minima relative to the mean.
    """
    ts = check_range(np.atleast_1d(sun_zenith), "sun_zenith", *preetham.SUN_ZENITH_RANGE, unit="rad")
    tu = check_range(np.atleast_1d(turbidity), "turbidity", *preetham.TURBIDITY_RANGE)
    if ts.ndim != 1 or tu.ndim != 1:
        raise ValueError(f"sun_zenith and turbidity must be 1-D, got shapes {ts.shape} and {tu.shape}")
    if not isinstance(objective, Objective):
        raise TypeError(f"objective must be an irradiance_fit.Objective, got {objective!r}")
    results = list(mapper(constrained_point, [(float(a), float(b), objective, colourspace) for a in ts for b in tu]))
    coeffs = np.stack([r[0] for r in results]).reshape(ts.size, tu.size, 9, 3)
    minimum = np.stack([r[1]["minimum"] for r in results]).reshape(ts.size, tu.size, 3)
    return coeffs, minimum


# --------------------------------------------------------------------------- #
# The table
# --------------------------------------------------------------------------- #
def fit_irradiance_table(sun_zenith: ArrayLike, turbidity: ArrayLike, coeffs: ArrayLike,
                         degrees: tuple[int, int] = (13, 7)) -> tuple[NDArray[np.float64], NDArray[np.int64], float]:
    """
    Fit irradiance coefficients at points with the sky table's polynomial (:func:`skysh.table.fit.fit_table`).

    ``sun_zenith``, ``turbidity``: (P,) points (radians; turbidity); ``coeffs``: (P, 9, 3)
    irradiance coefficients there (m < 0 rows ignored); ``degrees``: (d_theta, d_tau), every band.

    Returns the (n_terms, 6, 3) Chebyshev coefficients of the **radiance-equivalent** m >= 0 rows
    over the luminance scale (the sky table's exact form; the runtime multiplies by A_l), the
    (3, 2) degrees and the largest condition number solved. Residuals are weighted by the inverse
    of each point's mean irradiance per channel.
    """
    e = as_float_array(coeffs, "coeffs")
    if e.ndim != 3 or e.shape[1:] != (9, 3):
        raise ValueError(f"coeffs must have shape (P, 9, 3), got {e.shape}")
    half = radiance_equivalent(e)[:, list(HALF_ROWS)]
    per_band = np.tile(np.asarray(degrees, dtype=np.int64), (3, 1))
    table, condition = fit.fit_table(np.asarray(sun_zenith), np.asarray(turbidity), half, Y00 * e[:, 0], per_band)
    return table, per_band, condition


def evaluate_irradiance_table(table: NDArray, degrees: NDArray, sun_zenith: ArrayLike,
                              turbidity: ArrayLike) -> NDArray[np.float64]:
    """The tabulated irradiance at (P,) points: (P, 9, 3) coefficients, sun at azimuth 0 (m < 0 rows zero)."""
    half = fit.evaluate_table(table, degrees, np.asarray(sun_zenith), np.asarray(turbidity))
    out = np.zeros((half.shape[0], 9, 3))
    out[:, list(HALF_ROWS)] = half
    return out * LOBE[:, None]


FIT_ERROR_POINTS: tuple[int, int] = (128, 8)
"""Held-out points solved exactly for the table's fit error: random ones plus the 4 corners, and per edge."""

NONNEG_POINTS: tuple[int, int] = (10_000, 500)
"""Held-out points of the non-negativity certificate: random ones plus the 4 corners, and per edge (12,004)."""

HELD_OUT_SEED: int = 2018
"""Seed of the fit-error points (the certificate's: + 7); the sky table's is 2008."""


def build_table(grid: tuple[int, int], degrees: tuple[int, int] = (13, 7), objective: Objective = RECOMMENDED,
                colourspace: str = "sRGB", mapper: Callable[[Callable, Iterable], Iterable] = map,
                held_out: tuple[int, int] = FIT_ERROR_POINTS) -> tuple[NDArray[np.float64], NDArray[np.int64], dict[str, Any]]:
    """
    The coefficient file's irradiance table and its metadata block (``tools/fit_sky.py``).

    Solves ``objective`` on the sky table's Chebyshev ``grid`` (:func:`constrained_irradiance_grid`),
    fits it (:func:`fit_irradiance_table`, ``degrees``), measures the fit error against exact
    solves at ``held_out`` points (:data:`FIT_ERROR_POINTS`) and certifies the result: the exact
    minimum (:func:`sphere_minimum`) of the tabulated irradiance at :data:`NONNEG_POINTS`.
    Deterministic (the same grid, points and solver give the same bytes).

    Returns
    -------
    table, degrees, block
        (n_terms, 6, 3), (3, 2) and the ``tables.irradiance`` block: ``objective``, ``margin``,
        ``fit_error``, ``nonnegativity`` (``negative`` points, ``lowest`` minimum / mean), settings.

    Raises
    ------
    ModuleNotFoundError
        Before any work, if the solver is missing (:func:`require_solver`).
    RuntimeError
        If the tabulated irradiance is negative at any certificate point (raise the margin).
    """
    from importlib.metadata import version

    require_solver("the irradiance table")  # the block records the solver's versions: refuse before the grid
    gts, gtu = fit.chebyshev_grid(grid)
    coeffs, grid_min = constrained_irradiance_grid(gts.reshape(grid)[:, 0], gtu.reshape(grid)[0], objective, mapper,
                                                   colourspace)
    table, per_band, condition = fit_irradiance_table(gts, gtu, coeffs.reshape(-1, 9, 3), degrees)
    hts, htu = fit._held_out(held_out, HELD_OUT_SEED)
    exact = np.stack([r[0] for r in mapper(constrained_point, [(a, b, objective, colourspace)
                                                                for a, b in zip(hts.tolist(), htu.tolist())])])
    d = evaluate_irradiance_table(table, per_band, hts, htu) - exact
    error = np.max(np.maximum(-sphere_minimum(d), -sphere_minimum(-d)) / (Y00 * exact[:, 0]), axis=1)
    nts, ntu = fit._held_out(NONNEG_POINTS, HELD_OUT_SEED + 7)
    dense = evaluate_irradiance_table(table, per_band, nts, ntu)
    lowest = np.min(sphere_minimum(dense) / (Y00 * dense[:, 0]), axis=1)
    negative, k, w = int(np.sum(lowest < 0.0)), int(np.argmin(lowest)), int(np.argmax(error))
    if negative:
        raise RuntimeError(f"the tabulated irradiance is negative at {negative} of {nts.size} held-out points (lowest "
                           f"{lowest[k]:.3g} of the mean): raise the objective's margin ({objective.margin:g})")
    kinds = "uniform random in (sun zenith, T), the 4 corners, {} per edge"
    block = {
        "description": "3-band sky irradiance closest to the true one subject to being non-negative on the whole sphere "
        "(skysh.table.irradiance_fit, issue 18), tabulated in the sky table's form",
        "objective": {**asdict(objective), "chroma_floor": CHROMA_FLOOR, "truth_bands": TRUTH_BANDS,
                      "truth_theta_nodes": TRUTH_THETA_NODES, "solver": f"cvxpy {version('cvxpy')}, Clarabel "
                      f"{version('clarabel')}"},
        "margin": objective.margin,
        "grid": {"kind": "Chebyshev-Gauss nodes", "shape": list(grid), "lowest": float(grid_min.min())},
        "condition_number": condition,
        "fit_error": {"definition": "max over the sphere (exact) of |tabulated - exact optimum| / the optimum's mean "
                      "irradiance, worst channel", "points": int(hts.size), "seed": HELD_OUT_SEED,
                      "kinds": kinds.format(held_out[1]), "worst": float(error[w]), "median": float(np.median(error)),
                      "worst_at": [float(hts[w]), float(htu[w])]},
        "nonnegativity": {"definition": "exact minimum over the sphere (sphere_minimum, the S-lemma dual) of the "
                          "tabulated irradiance / its mean irradiance, lowest channel", "points": int(nts.size),
                          "seed": HELD_OUT_SEED + 7, "kinds": kinds.format(NONNEG_POINTS[1]), "negative": negative,
                          "lowest": float(lowest[k]), "lowest_at": [float(nts[k]), float(ntu[k])]},
    }
    return table, per_band, block
