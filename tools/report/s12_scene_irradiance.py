"""
Section 12: sky + sun + ground irradiance against brute force, by bands (issue 15)
==================================================================================

The runtime's ``SkySH.coefficients(..., sun=True, ground_albedo=rho, irradiance=True)``
(its defaults for irradiance: no Gibbs filter; the sky deringed, or at 3 bands its
certified irradiance table when the file has one) reconstructed with :func:`skysh.sh.basis.basis`,
against a brute-force integration of the full scene radiance:

-   the Preetham sky (:func:`skysh.model.preetham.radiance`) above the horizon, integrated per
    normal n over its *lune* {z > 0, n.w > 0} with a product Gauss rule in coordinates
    about the axis a = z x n that both bounding great circles contain (so the horizon
    and the clamped cosine's terminator are panel edges, not kinks inside a panel),
    split at the sun (the sky's conical kink sits on a panel corner);
-   the sun (:func:`skysh.model.solar.illuminance_rgb`, the spectral model, not the runtime's
    fitted table) as a delta of its illuminance: ``E_sun max(0, n.s)``;
-   a Lambertian ground of albedo rho below the horizon, radiance ``rho E_h / pi`` with
    E_h the brute-force horizontal irradiance of sky and sun, integrated over the lower
    lune {z < 0, n.w > 0} with the same rule.

Nothing here goes through the SH code: no projection, no clamped-cosine factors. The
rule at n = z (respectively -z) is the plain upper (lower) hemisphere; with unit radiance
it gives ``pi (1 +- n_z) / 2`` (``tests/test_error_report.py`` checks both).

Lune coordinates: with a = unit(z x n) (x when n = +-z), q = z x a and
``w = cos t a + sin t (cos psi z + sin psi q)``, dw = sin t dt dpsi, z > 0 iff
cos psi > 0, and ``n.w = sin t cos(psi - psi_n)`` with psi_n = -arccos(n_z). The sky
lune is t in [0, pi], psi in [-pi/2, psi_n + pi/2]; the ground lune psi in
[psi_n - pi/2, -pi/2].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import irradiance_study as study  # tools/
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from report.common import Context, Section, pct, sig, style_axes
from skysh.model import preetham, solar
from skysh.sh import basis as sh

NUMBER: int = 12
TITLE: str = "Scene irradiance against brute force"
BANDS: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7)
"""Band counts compared (the shipped file's)."""
PARTS: tuple[str, ...] = ("sky, not deringed", "sky", "sun", "ground", "total")
"""The parts whose errors are measured, each runtime part against its brute-force part: the sky without
deringing (truncation and ringing only), the sky as the runtime gives it (deringed), the sun (its windowed
delta), the ground, and their total."""
SUMMED: tuple[str, ...] = ("sky", "sun", "ground")
"""The parts whose sum is the total."""
SUN_AZIMUTH: float = 0.6
"""Sun azimuth of every scene, radians: off the x axis, so the runtime's Z rotation (Habel eq. 4) is in the comparison."""
NORMAL_CHUNK: int = 64
"""Normals per block of the lune quadrature (64 x 4 x 32^2 directions, about 6 MB per coordinate)."""
EZ: NDArray[np.float64] = np.array([0.0, 0.0, 1.0])
"""The zenith (Z up)."""
POLAR_TOL: float = 1e-12
"""|z x n| below this: n is a pole, and the lune axis is taken as x (any horizontal axis will do)."""
ERROR_FLOOR: float = 1e-9
"""Errors are plotted no lower than this fraction of the mean (a log axis cannot show the ground's exact 0)."""


@dataclass(frozen=True)
class Scene:
    """One outdoor scene: sun zenith (degrees), turbidity, ground albedo (a number or an RGB triple in [0, 1])."""

    sun_zenith_deg: float
    turbidity: float
    albedo: float | tuple[float, float, float]

    @property
    def label(self) -> str:
        albedo = f"{self.albedo:g}" if isinstance(self.albedo, float) else "(" + ", ".join(f"{a:g}" for a in self.albedo) + ")"
        return f"{self.sun_zenith_deg:g} deg, T {self.turbidity:g}, rho {albedo}"


@dataclass(frozen=True)
class Sizes:
    """Sizes of the section (``SIZES[plan.name]``)."""

    scenes: tuple[Scene, ...]
    normal_nodes: int  # Gauss nodes in z of the normals (2 n^2 normals, sh.quadrature_rule)
    lune_nodes: int  # Gauss nodes per panel of the lune rule (4 n^2 directions per normal)
    check_nodes: int  # a coarser lune rule: the convergence check


SIZES: dict[str, Sizes] = {
    "quick": Sizes((Scene(45.0, 3.0, 0.2), Scene(85.0, 5.0, (0.35, 0.3, 0.2))), 8, 16, 12),
    "full": Sizes((Scene(20.0, 2.5, 0.2), Scene(45.0, 3.0, 0.25), Scene(70.0, 4.0, (0.35, 0.3, 0.2)),
                   Scene(85.0, 5.0, 0.3), Scene(89.0, 6.0, 0.8)), 24, 32, 24),
}
"""Quick: 2 scenes, 128 normals, 1,024 directions per normal; full: 5 scenes (sun from 20 to 89 degrees,
turbidity 2.5 to 6, grey and coloured grounds up to snow), 1,152 normals, 4,096 directions per normal."""


# --------------------------------------------------------------------------- #
# The brute force
# --------------------------------------------------------------------------- #
def lune_frames(normals: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Per normal (M, 3): the lune axis a (M, 3), q = z x a (M, 3) and psi_n = -arccos(n_z) (M,)."""
    n = np.asarray(normals, dtype=np.float64)
    a = np.cross(EZ, n)
    length = np.linalg.norm(a, axis=-1)
    polar = length < POLAR_TOL
    a = np.where(polar[:, None], [1.0, 0.0, 0.0], a / np.where(polar, 1.0, length)[:, None])
    return a, np.cross(EZ, a), -np.arccos(np.clip(n[:, 2], -1.0, 1.0))


def gauss_panels(lo: NDArray, hi: NDArray, split: NDArray, nodes: int) -> tuple[NDArray, NDArray]:
    """Gauss-Legendre on [lo, split] and [split, hi] per row: nodes and weights (M, 2 nodes)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    parts = [(a[:, None] + (b - a)[:, None] * 0.5 * (x + 1.0), (b - a)[:, None] * 0.5 * w) for a, b in ((lo, split), (split, hi))]
    return np.concatenate([p[0] for p in parts], axis=1), np.concatenate([p[1] for p in parts], axis=1)


def lune_rule(normals: NDArray, sun: NDArray, nodes: int) -> tuple[NDArray, NDArray]:
    """Directions (M, K, 3) and weights (M, K) over each normal's sky lune, n.w folded in: sum w L = E_sky(n).

    K = 4 nodes^2: t split at the sun, psi split at the sun when it lies in the lune (else halfway).
    """
    a, q, psi_n = lune_frames(normals)
    m = a.shape[0]
    lo, hi = np.full(m, -0.5 * math.pi), psi_n + 0.5 * math.pi
    psi_sun = np.arctan2(q @ sun, sun[2])
    split = np.where((psi_sun > lo) & (psi_sun < hi), psi_sun, 0.5 * (lo + hi))
    t, wt = gauss_panels(np.zeros(m), np.full(m, math.pi), np.arccos(np.clip(a @ sun, -1.0, 1.0)), nodes)
    p, wp = gauss_panels(lo, hi, split, nodes)
    u = np.cos(p)[..., None] * EZ + np.sin(p)[..., None] * q[:, None, :]  # (M, P, 3)
    st = np.sin(t)
    dirs = np.cos(t)[:, :, None, None] * a[:, None, None, :] + st[:, :, None, None] * u[:, None, :, :]
    weights = (wt * st * st)[:, :, None] * (wp * np.cos(p - psi_n[:, None]))[:, None, :]
    return dirs.reshape(m, -1, 3), weights.reshape(m, -1)


def ground_view(normals: NDArray, nodes: int) -> NDArray:
    """int over the lower lune of n.w dw per normal (M,): the irradiance of a unit-radiance ground."""
    _, _, psi_n = lune_frames(normals)
    m = psi_n.shape[0]
    lo, hi = psi_n - 0.5 * math.pi, np.full(m, -0.5 * math.pi)
    t, wt = gauss_panels(np.zeros(1), np.full(1, math.pi), np.full(1, 0.5 * math.pi), nodes)
    p, wp = gauss_panels(lo, hi, 0.5 * (lo + hi), nodes)
    return float(np.sum(wt * np.sin(t) ** 2)) * np.sum(wp * np.cos(p - psi_n[:, None]), axis=1)


def sky_irradiance(normals: NDArray, sun_zenith: float, turbidity: float, sun_azimuth: float, nodes: int) -> NDArray:
    """The Preetham sky's irradiance at the normals (M, 3), linear sRGB lux-scaled, by the lune rule."""
    sun = solar.sun_direction(sun_zenith, sun_azimuth)
    out = np.empty((normals.shape[0], 3))
    for start in range(0, normals.shape[0], NORMAL_CHUNK):
        dirs, weights = lune_rule(normals[start : start + NORMAL_CHUNK], sun, nodes)
        radiance = preetham.radiance(dirs.reshape(-1, 3), sun_zenith, sun_azimuth, turbidity).reshape(dirs.shape)
        out[start : start + NORMAL_CHUNK] = np.einsum("mk,mkc->mc", weights, radiance)
    return out


def scene_truth(scene: Scene, normals: NDArray, nodes: int) -> dict[str, NDArray]:
    """Brute-force irradiance of each part at the normals (M, 3), and E_h (3,) of sky + sun."""
    ts = math.radians(scene.sun_zenith_deg)
    sky = sky_irradiance(normals, ts, scene.turbidity, SUN_AZIMUTH, nodes)
    sun_rgb = solar.illuminance_rgb(ts, scene.turbidity)
    sun = np.maximum(0.0, normals @ solar.sun_direction(ts, SUN_AZIMUTH))[:, None] * sun_rgb
    e_h = sky_irradiance(EZ[None], ts, scene.turbidity, SUN_AZIMUTH, nodes)[0] + math.cos(ts) * sun_rgb
    ground = ground_view(normals, nodes)[:, None] * (np.asarray(scene.albedo) * e_h / math.pi)
    return {PARTS[0]: sky, "sky": sky, "sun": sun, "ground": ground, "total": sky + sun + ground, "e_h": e_h}


# --------------------------------------------------------------------------- #
# The runtime and the comparison
# --------------------------------------------------------------------------- #
def runtime_parts(ctx: Context, scene: Scene, normals: NDArray, bands: int) -> dict[str, NDArray]:
    """The runtime's irradiance of each part at the normals (M, 3): sky, + sun, + ground (differences of calls)."""
    ts, basis = math.radians(scene.sun_zenith_deg), sh.basis(normals, bands)
    args = (ts, scene.turbidity, SUN_AZIMUTH)
    raw = basis @ ctx.sky.coefficients(*args, bands=bands, irradiance=True, dering=False)
    sky = basis @ ctx.sky.coefficients(*args, bands=bands, irradiance=True)
    with_sun = basis @ ctx.sky.coefficients(*args, bands=bands, irradiance=True, sun=True)
    total = basis @ ctx.sky.coefficients(*args, bands=bands, irradiance=True, sun=True, ground_albedo=scene.albedo)
    return {PARTS[0]: raw, "sky": sky, "sun": with_sun - sky, "ground": total - with_sun, "total": total}


def errors(predicted: dict[str, NDArray], truth: dict[str, NDArray], weights: NDArray) -> NDArray:
    """(parts, 2): worst |error| over normals and RGB and the RMS (worst channel), relative to the mean total irradiance."""
    mean = weights @ truth["total"] / np.sum(weights)
    out = np.empty((len(PARTS), 2))
    for k, part in enumerate(PARTS):
        relative = (predicted[part] - truth[part]) / mean
        out[k] = np.max(np.abs(relative)), np.max(np.sqrt(weights @ relative**2 / np.sum(weights)))
    return out


def compute(ctx: Context) -> dict[str, Any]:
    """Brute force per scene (and its convergence), the runtime by bands, errors (scenes, bands, parts, 2)."""
    sizes = SIZES[ctx.plan.name]
    normals, weights = sh.quadrature_rule(sizes.normal_nodes)
    table = np.empty((len(sizes.scenes), len(BANDS), len(PARTS), 2))
    convergence, ground_share, sun_share = [], [], []
    with ctx.bar(len(sizes.scenes), "12. sky + sun + ground") as bar:
        for i, scene in enumerate(sizes.scenes):
            truth = scene_truth(scene, normals, sizes.lune_nodes)
            mean = weights @ truth["total"] / np.sum(weights)
            coarse = sky_irradiance(normals, math.radians(scene.sun_zenith_deg), scene.turbidity, SUN_AZIMUTH,
                                    sizes.check_nodes)
            convergence.append(float(np.max(np.abs(coarse - truth["sky"]) / mean)))
            sun_share.append(float(np.max(weights @ truth["sun"] / np.sum(weights) / mean)))
            ground_share.append(float(np.max(weights @ truth["ground"] / np.sum(weights) / mean)))
            for j, bands in enumerate(BANDS):
                table[i, j] = errors(runtime_parts(ctx, scene, normals, bands), truth, weights)
            bar.update(1)
    return {"scenes": sizes.scenes, "errors": table, "convergence": convergence, "normals": int(normals.shape[0]),
            "table_at_3": study.runtime_has_irradiance_table(ctx.sky),
            "lune": (sizes.lune_nodes, sizes.check_nodes), "sun_share": sun_share, "ground_share": ground_share}


# --------------------------------------------------------------------------- #
# Rendering
# --------------------------------------------------------------------------- #
def _figure(ctx: Context, d: dict[str, Any]) -> str:
    e = np.maximum(100.0 * d["errors"], 100.0 * ERROR_FLOOR)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    colours = plt.get_cmap("tab10").colors  # type: ignore[attr-defined]  # a ListedColormap
    total = PARTS.index("total")
    for i, scene in enumerate(d["scenes"]):
        axes[0].plot(BANDS, e[i, :, total, 0], "o-", color=colours[i], label=f"{scene.label}: worst")
        axes[0].plot(BANDS, e[i, :, total, 1], "s--", color=colours[i], label="RMS", alpha=0.7)
    style_axes(axes[0], "SH bands N", "irradiance error (% of the mean irradiance)",
               "Sky + sun + ground: runtime against brute force", ylog=True, legend={"fontsize": 7, "ncol": 2})
    for k, part in enumerate(PARTS):
        look = {"color": "black", "linewidth": 3.0, "zorder": 1} if part == "total" else {"color": colours[k], "zorder": 2}
        axes[1].plot(BANDS, e[:, :, k, 0].max(axis=0), "o-", label=f"{part}: worst", **look)
        axes[1].plot(BANDS, e[:, :, k, 1].max(axis=0), "s--", label=f"{part}: RMS", alpha=0.7, **look)
    style_axes(axes[1], "SH bands N", f"irradiance error (% of the mean; shown >= {100 * ERROR_FLOOR:g}%)",
               f"By part, worst over the {len(d['scenes'])} scenes", ylog=True, legend={"fontsize": 7, "ncol": 2})
    for ax in axes:
        ax.set_xticks(BANDS)
    return ctx.save(fig, "s12_scene_irradiance.png")


def _dominant(d: dict[str, Any]) -> str:
    """One sentence per band range: which part holds the worst error (worst over scenes)."""
    worst = d["errors"][:, :, [PARTS.index(p) for p in SUMMED], 0].max(axis=0)  # (bands, parts summed)
    leaders = [SUMMED[int(np.argmax(row))] for row in worst]
    runs: list[tuple[str, list[int]]] = []
    for bands, leader in zip(BANDS, leaders):
        if runs and runs[-1][0] == leader:
            runs[-1][1].append(bands)
        else:
            runs.append((leader, [bands]))
    spans = [f"{'N = ' + str(b[0]) if len(b) == 1 else f'N = {b[0]}-{b[-1]}'}: the {part}" for part, b in runs]
    return "; ".join(spans)


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, e = Section(NUMBER, TITLE), d["errors"]
    r = solar.SUN_ANGULAR_RADIUS
    nodes, check = d["lune"]
    s.text(
        "`SkySH.coefficients(sun_zenith, turbidity, 0.6, bands=N, irradiance=True, sun=True, ground_albedo=rho)` "
        "(runtime defaults: no Gibbs filter; the sky deringed, or at N = 3 its irradiance table"
        + (")" if d["table_at_3"] else ", which this file lacks)") + " reconstructed with `skysh.sh.basis.basis` on "
        f"{d['normals']:,} Gauss normals, against a brute-force integral of the full scene radiance per normal: the "
        "Preetham sky over the normal's lune {z > 0, n.w > 0} (a product Gauss rule about the axis z x n, so the "
        "horizon and the clamped cosine's edge are panel edges, split at the sun; "
        f"{4 * nodes * nodes:,} directions per normal), plus the sun as a delta of its illuminance "
        "(`skysh.model.solar.illuminance_rgb`, the spectral model), plus a Lambertian ground of radiance rho E_h / pi "
        "(E_h the brute-force horizontal irradiance of sky and sun) over the lower lune. No SH enters the truth. "
        "Errors relative to the scene's mean irradiance (per channel, worst channel): worst over normals and RMS. "
        f"The {4 * check * check:,}-direction rule agrees with it to {sig(100 * max(d['convergence']))}% of the mean.",
        "The sun as a delta: the runtime's sun *is* a delta (a directional light of illuminance E_sun = L_sun x "
        "solid angle). The uniform disk of angular radius r = "
        f"{sig(math.degrees(r))} deg gives E_sun (n.s) (1 + cos r) / 2 wherever it lies wholly above the surface, a "
        f"relative difference (1 - cos r) / 2 = {sig((1 - math.cos(r)) / 2)}; only for normals within r of the "
        f"sun's terminator (|n.s| < sin r = {sig(math.sin(r))}, that share of the sphere) do they differ by up to "
        f"E_sun sin r, i.e. (E_sun being 4 x the sun's share of the mean irradiance) at most "
        f"{pct(4 * max(d['sun_share']) * math.sin(r))} of the mean here, on that thin band only. The sun's share of "
        "the mean irradiance is "
        f"{pct(min(d['sun_share']))} to {pct(max(d['sun_share']))} over these scenes, the ground's "
        f"{pct(min(d['ground_share']))} to {pct(max(d['ground_share']))}.",
    )
    total = PARTS.index("total")
    s.table(["bands", *[sc.label for sc in d["scenes"]]],
            [[b, *[f"{pct(e[i, j, total, 0])} / {pct(e[i, j, total, 1])}" for i in range(len(d["scenes"]))]]
             for j, b in enumerate(BANDS)])
    s.text("Above: worst / RMS error of the total irradiance per scene. Below: each part against its own brute "
           "force, worst over the scenes, as worst / RMS: the sky without deringing (truncation and ringing only), "
           "the sky as the runtime gives it by default (deringed alone, before the sun and the ground are added), "
           "the sun (the windowed delta), the ground (its zonal SH, with E_h from the fitted table's c_10 and the sun "
           "table). Bands 4 and 6 add nothing to irradiance (A_l = 0 for odd l >= 3): N = 4 repeats N = 3 and N = 6 "
           "repeats N = 5, up to the deringing's choice of window"
           + ("; but at N = 3 the runtime's default sky is its certified irradiance table (issue 18, section 11: "
              "non-negative without a deringing search), whence N = 3 beats N = 4." if d["table_at_3"] else "."))
    s.table(["bands", *PARTS], [[b, *[f"{pct(e[:, j, k, 0].max())} / {pct(e[:, j, k, 1].max())}"
                                      for k in range(len(PARTS))]] for j, b in enumerate(BANDS)])
    raw, sky, j7 = PARTS.index(PARTS[0]), PARTS.index("sky"), BANDS.index(7)
    s.text(f"Which part holds the worst error: {_dominant(d)}. The sun's error is that of a clamped cosine "
           "truncated to N bands and windowed so that it cannot go negative, times the sun's illuminance. Of the "
           f"sky's error at 7 bands ({pct(e[:, j7, sky, 0].max())}), the truncation alone is "
           f"{pct(e[:, j7, raw, 0].max())}: the rest is the deringing window, which the runtime fits to the sky alone "
           "although the sun and the ground it then adds are non-negative too. The ground is exact from N = 2 "
           "(only bands 0 and 1 reach its irradiance): what remains is the fitted c_10 and sun table in E_h.")
    s.figure(_figure(ctx, d), "Sky + sun + ground irradiance against brute force, by bands")
    j3 = BANDS.index(3)
    ctx.note("Sky + sun + ground irradiance, 3 bands: worst / RMS error against brute force (of the mean)",
             f"{pct(e[:, j3, total, 0].max())} / {pct(e[:, j3, total, 1].max())}", "")
    return s
