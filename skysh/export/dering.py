"""
Deringing of 3-band SH in C, GLSL, HLSL and JavaScript
=====================================================

:func:`dering_source` returns one self-contained function that windows 3-band radiance SH
in place as :func:`skysh.post.dering.dering` does: the same table (baked in), the same exact
minimum per row (eigendecomposition of Q, here by cyclic Jacobi rotations; the same
start, Newton steps and allowance), the least row non-negative in all three channels.

-   C: ``int name(double c[9][3], double scales_out[3])``;
-   GLSL, HLSL: ``int name(inout float c[27], out float scales_out[3])``, c[3 k + ch];
-   JavaScript: ``function name(c, scales_out)``, c[k][ch] (arrays of numbers).

Each returns 1 when no row is non-negative (the last row is then applied), else 0. C and
JavaScript (double) pick Python's row; GLSL and HLSL (float, with float guards and a
256-ulp allowance) may pick a later row near a tie and report failure for lights whose
last-row margin (1e-9 of the mean) is below float's resolution. C needs ``<math.h>``;
GLSL 3.10 ES / 4.0+.
"""

from __future__ import annotations

import re

from skysh.checks import check_choice
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

__all__ = ["LANGUAGES", "dering_source"]

LANGUAGES: tuple[str, ...] = ("c", "glsl", "hlsl", "js")
"""Languages of :func:`dering_source`."""

_GUARDS: dict[str, tuple[float, float, float, float]] = {
    "double": (shmin.TINY, shmin.FLOOR, shmin.POLE, shmin.ALLOWANCE),
    "float": (1e-30, 1e-18, 1e-12, shmin.ALLOWANCE / 2.0**-52 * 2.0**-23)}
"""(tiny, floor, pole, allowance) per precision: Python's in double; in float the same roles
within float's range (floor^2 and a / pole^3 normal and finite for |f| <= pi)."""

_BODY = """
  INT pass[NROWS];
  for (INT r = 0; r < NROWS; r++) { pass[r] = 1; }
  for (INT ch = 0; ch < 3; ch++) {
    REAL m = 0.0;
    for (INT k = 0; k < 9; k++) { m = MAX(m, ABS(IN(k, ch))); }
    if (m > 0.0) {
      REAL f[9];
      NORMALISE
      REAL c0 = Y00 * f[0];
      REAL g[3];
      g[0] = -KL * f[3]; g[1] = -KL * f[1]; g[2] = KL * f[2];
      REAL A[9];
      A[0] = K2 * f[8] - K0 * f[6]; A[4] = -K0 * f[6] - K2 * f[8]; A[8] = 2.0 * K0 * f[6];
      A[1] = 0.5 * KB * f[4]; A[3] = A[1]; A[2] = -0.5 * KB * f[7]; A[6] = A[2]; A[5] = -0.5 * KB * f[5]; A[7] = A[5];
      REAL V[9];
      for (INT k = 0; k < 9; k++) { V[k] = (k % 4 == 0) ? 1.0 : 0.0; }
      for (INT sweep = 0; sweep < 8; sweep++) {
        for (INT pair = 0; pair < 3; pair++) {
          INT p = (pair == 2) ? 1 : 0;
          INT q = (pair == 0) ? 1 : 2;
          REAL apq = A[p * 3 + q];
          if (apq != 0.0) {
            REAL theta = (A[q * 3 + q] - A[p * 3 + p]) / (2.0 * apq);
            REAL t = ((theta >= 0.0) ? 1.0 : -1.0) / (ABS(theta) + SQRT(theta * theta + 1.0));
            REAL cs = 1.0 / SQRT(t * t + 1.0);
            REAL sn = t * cs;
            for (INT k = 0; k < 3; k++) {
              REAL akp = A[k * 3 + p]; REAL akq = A[k * 3 + q]; REAL vkp = V[k * 3 + p]; REAL vkq = V[k * 3 + q];
              A[k * 3 + p] = cs * akp - sn * akq; A[k * 3 + q] = sn * akp + cs * akq;
              V[k * 3 + p] = cs * vkp - sn * vkq; V[k * 3 + q] = sn * vkp + cs * vkq;
            }
            for (INT k = 0; k < 3; k++) {
              REAL apk = A[p * 3 + k]; REAL aqk = A[q * 3 + k];
              A[p * 3 + k] = cs * apk - sn * aqk; A[q * 3 + k] = sn * apk + cs * aqk;
            }
          }
        }
      }
      REAL lam[3];
      REAL a[3];
      for (INT i = 0; i < 3; i++) {
        lam[i] = A[i * 4];
        REAL gam = V[i] * g[0] + V[3 + i] * g[1] + V[6 + i] * g[2];
        a[i] = 0.25 * gam * gam;
      }
      for (INT i = 0; i < 2; i++) {
        for (INT j = 0; j < 2 - i; j++) {
          if (lam[j] > lam[j + 1]) {
            REAL tl = lam[j]; lam[j] = lam[j + 1]; lam[j + 1] = tl; REAL ta = a[j]; a[j] = a[j + 1]; a[j + 1] = ta;
          }
        }
      }
      for (INT r = 0; r < NROWS; r++) {
        REAL s1 = TAB1[r];
        REAL s2 = TAB2[r];
        REAL d[3];
        REAL ar[3];
        REAL x = FLOOR;
        REAL cum = 0.0;
        for (INT i = 0; i < 3; i++) {
          d[i] = s2 * lam[i] - s2 * lam[0]; ar[i] = a[i] * (s1 * s1); cum += ar[i]; x = MAX(x, SQRT(cum) - d[i]);
        }
        REAL low = x;
        for (INT it = 0; it <= STEPS; it++) {
          REAL s = 0.0;
          REAL tt = 0.0;
          for (INT i = 0; i < 3; i++) {
            REAL w = 1.0 / (d[i] + x);
            REAL aw2 = ar[i] * w * w;
            s += aw2; tt += aw2 * w;
          }
          x = MAX(x + (SQRT(s) - 1.0) * s / (tt + TINY), low);
          if (it == 0) {
            REAL big = 0.0;
            for (INT k = 1; k < 3; k++) {
              big += ar[k - 1];
              REAL c0s = 0.0;
              REAL t0s = 0.0;
              for (INT i = k; i < 3; i++) {
                REAL far = MAX(d[i] - d[k - 1], POLE);
                REAL u = ar[i] / (far * far);
                c0s += u; t0s += u / far;
              }
              t0s += TINY;
              REAL cub = big / (4.0 * t0s);
              REAL near = MIN(SQRT(big / (2.0 * MAX(1.0 - c0s, 0.0) + TINY)), CBRT(cub));
              x = MAX(x, MAX((SQRT(c0s) - 1.0) * c0s / t0s, near) - d[k - 1]);
            }
            low = x;
          }
        }
        REAL sum = 0.0;
        for (INT i = 0; i < 3; i++) { sum += ar[i] / (d[i] + x); }
        if (c0 + s2 * lam[0] - x - sum < ROUND) { pass[r] = 0; }
      }
    }
  }
  INT row = NROWS - 1;
  INT failed = 1;
  for (INT r = NROWS - 1; r >= 0; r--) { if (pass[r] == 1) { row = r; failed = 0; } }
  scales_out[0] = 1.0; scales_out[1] = TAB1[row]; scales_out[2] = TAB2[row];
  for (INT k = 0; k < 9; k++) {
    REAL s = (k == 0) ? 1.0 : ((k < 4) ? TAB1[row] : TAB2[row]);
    for (INT ch = 0; ch < 3; ch++) { IN(k, ch) = IN(k, ch) * s; }
  }
  return failed;
"""
"""The function body in a C-like notation shared by every language (Python's steps: the
proven start, one Newton step, the proven cluster bounds, STEPS more)."""

_NORMALISE = {
    "c": "int e; frexp(m, &e);\n      for (int k = 0; k < 9; k++) { f[k] = ldexp(c[k][ch], -e) * KER[k]; }",
    "glsl": "float inv = exp2(-floor(log2(m)) - 1.0);\n"
            "      for (int k = 0; k < 9; k++) { f[k] = c[k * 3 + ch] * inv * KER[k]; }",
    "js": "let e = Math.floor(Math.log2(m)) + 1;\n      if (m < Math.pow(2, e - 1)) { e -= 1; }\n"
          "      if (m >= Math.pow(2, e)) { e += 1; }\n      const h = Math.floor(e / 2);\n"
          "      for (let k = 0; k < 9; k++) { f[k] = c[k][ch] * Math.pow(2, -h) * Math.pow(2, h - e) * KER[k]; }"}
"""Per language: f = c / 2^e times the kernel, e the exponent of max |c| as numpy.frexp gives it
(GLSL, HLSL: a power of two near it), an exact scaling."""
_NORMALISE["hlsl"] = _NORMALISE["glsl"]

_FUNCTIONS: dict[str, dict[str, str]] = {
    "c": {"SQRT": "sqrt", "ABS": "fabs", "MAX": "fmax", "MIN": "fmin", "CBRT": "cbrt"},
    "glsl": {"SQRT": "sqrt", "ABS": "abs", "MAX": "max", "MIN": "min", "CBRT": "cbrt"},
    "js": {"SQRT": "Math.sqrt", "ABS": "Math.abs", "MAX": "Math.max", "MIN": "Math.min", "CBRT": "Math.cbrt"}}
"""The template's functions per language (GLSL and HLSL write cbrt(x), x >= 0, as pow(x, 1/3))."""
_FUNCTIONS["hlsl"] = _FUNCTIONS["glsl"]

_HEADS: dict[str, str] = {
    "c": "int {name}(double c[9][3], double scales_out[3]) {{",
    "glsl": "int {name}(inout float c[27], out float scales_out[3]) {{",
    "hlsl": "int {name}(inout float c[27], out float scales_out[3]) {{",
    "js": "function {name}(c, scales_out) {{"}


def _literal(value: float, precision: str) -> str:
    text = repr(float(value)) if precision == "double" else f"{float(value):.9g}"
    return text if any(ch in text for ch in ".en") else text + ".0"


def _array(name: str, values: list[float], language: str, precision: str) -> str:
    items, n = ", ".join(_literal(v, precision) for v in values), len(values)
    return {"c": f"  static const double {name}[{n}] = {{{items}}};", "glsl": f"  const float {name}[{n}] = float[{n}]({items});",
            "hlsl": f"  static const float {name}[{n}] = {{{items}}};", "js": f"  const {name} = [{items}];"}[language]


def dering_source(language: str, target: str = "irradiance", name: str = "skysh_dering3") -> str:
    """
    Source text of a function that derings one 3-band RGB radiance SH in place.

    Parameters
    ----------
    language
        One of :data:`LANGUAGES`: ``"c"`` (double), ``"glsl"``, ``"hlsl"`` (float), ``"js"`` (double).
    target
        ``"irradiance"`` or ``"radiance"``: what must be non-negative (table and kernel baked in).
    name
        The function's name, an ASCII identifier.

    Returns
    -------
    str
        One self-contained function (signatures in the module docstring), no includes.
    """
    check_choice(language, "language", LANGUAGES)
    check_choice(target, "target", dering.DERING_TARGETS)
    if not (name.isidentifier() and name.isascii()):
        raise ValueError(f"name must be an ASCII identifier, got {name!r}")
    precision = "double" if language in ("c", "js") else "float"
    table = dering.window_table(3, target)
    tiny, floor, pole, allowance = _GUARDS[precision]
    consts = {"Y00": sh.Y00, "KL": sh.K_LINEAR, "KB": sh.K_PRODUCT, "K0": sh.K_ZONAL, "K2": sh.K_SECTORAL,
              "TINY": tiny, "FLOOR": floor, "POLE": pole, "ROUND": allowance}
    body = _BODY.replace("NORMALISE", _NORMALISE[language])
    body = re.sub(r"\b(" + "|".join(consts) + r")\b", lambda m: _literal(consts[m.group(1)], precision), body)
    body = body.replace("NROWS", str(len(table))).replace("STEPS", str(shmin.NEWTON_STEPS))
    if language in ("glsl", "hlsl"):
        body = re.sub(r"CBRT\((\w+)\)", r"pow(\1, 1.0 / 3.0)", body)
    body = re.sub(r"\b(SQRT|ABS|MAX|MIN|CBRT)\(", lambda m: _FUNCTIONS[language][m.group(1)] + "(", body)
    body = body.replace("IN(k, ch)", "c[k * 3 + ch]" if language in ("glsl", "hlsl") else "c[k][ch]")
    if language == "js":
        body = re.sub(r"(REAL|INT) (\w+)\[(\w+)\];", r"const \2 = new Array(\3).fill(0);", body)
        body = re.sub(r"\b(REAL|INT) ", "let ", body)
    else:
        body = re.sub(r"\bINT ", "int ", body).replace("REAL ", "double " if language == "c" else "float ")
    tables = "\n".join([_array("TAB1", table[:, 1].tolist(), language, precision),
                        _array("TAB2", table[:, 2].tolist(), language, precision),
                        _array("KER", dering.KERNELS[target][sh.band_of_index(3)].tolist(), language, precision)])
    doc = (f"/* skysh deringing, 3 bands, target {target} (generated by skysh.export.dering): windows the radiance "
           "SH c in place with the least table row that keeps the target non-negative; returns 1 if no row does "
           "(the last row is then applied), else 0. */")
    return f"{doc}\n{_HEADS[language].format(name=name)}\n{tables}{body}}}\n"
