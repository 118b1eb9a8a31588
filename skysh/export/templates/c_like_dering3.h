/*
 * Deringing of RGB radiance SH of 1 to 3 bands, and of 4 bands for irradiance, for C, GLSL and HLSL
 * (skysh/export/templates/c_like_dering3.h), as skysh.post.dering.dering does it (method "window"): the
 * least window position along the table SKYSH_DERING_TABLE (SKYSH_DERING_ROWS rows of SKYSH_DERING_BANDS
 * per-band factors, row-major; row 0 all ones), with the factors linear between neighbouring rows, whose
 * windowed target (the kernel SKYSH_DERING_KERNEL times the coefficients: irradiance or radiance) is
 * non-negative in all three channels. The target is a 3-band function (4-band irradiance: A_3 = 0), and
 * its exact minimum over the sphere (skysh.sh.minimum) is the minimum of c0 + g.u + u.A u over unit u:
 * the eigenvalues of A by cyclic Jacobi rotations (one decomposition serves every window: a window
 * (1, s1, s2) scales g by s1 and A by s2), then the secular equation's root by the proven start, one
 * Newton step, the proven cluster bounds and SKYSH_DERING_STEPS more steps; a window passes when that
 * minimum is at least SKYSH_DERING_ROUND in every channel.
 *
 * The search (skysh.post.dering.least_window): the least whole row r that passes; none: the last row,
 * failed; r = 0: position 0; else the least fraction k / SKYSH_DERING_LATTICE (k in 1 .. LATTICE) of
 * the step from row r - 1 whose window passes, by bisection on multiples of 1 / LATTICE from the guess
 * where the chord of the minimum between the two rows crosses zero (the minimum is concave in the
 * fraction, so the passing fractions form one interval ending at 1). Position (r - 1) + k / LATTICE.
 * In C, a function with a channel below 2^SKYSH_DERING_SUBNORMAL in every coefficient keeps whole rows,
 * each decided on its windowed coefficients as rounded (as Python: subnormal products round by more than
 * eps of the channel).
 *
 * SKYSH_DERING_NAME(c, scales_out, position_out) windows c in place, writes the per-band factors
 * applied to scales_out (band 0: 1) and the position to position_out[0], and returns 1 when no row
 * passes (the last row is then applied), else 0. C (64-bit reals whatever skysh_real is):
 * c[SKYSH_DERING_COUNT][3], c[k][channel]; GLSL and HLSL (float): inout c[3 SKYSH_DERING_COUNT],
 * c[3 k + channel]. Precondition: every coefficient finite (as every skysh output is; Python raises
 * otherwise). C checks it and returns 1 at once for a NaN or an inf, c untouched (scales_out 1,
 * position 0); the shaders do not check (a NaN would pass through their max and min as zero).
 * The numbers (the table, the kernel, the basis constants SKYSH_Y00, SKYSH_K_LINEAR,
 * SKYSH_K_PRODUCT, SKYSH_K_ZONAL, SKYSH_K_SECTORAL, the guards SKYSH_DERING_TINY, SKYSH_DERING_FLOOR,
 * SKYSH_DERING_POLE, float's least normal SKYSH_DERING_NORMAL) are #defines written before this file
 * (skysh.export.dering). 5..7 bands need the certificate (c_like_dering_certificate_c.h), C only: its
 * cost per call (skysh.export.dering.CERTIFICATE_COST, measured by python
 * tests/export/test_export_dering_certificate.py) is too much for a shader, whose dering option
 * refuses there.
 */

/* Per channel ch of c windowed by row `row` of tab (row 0: as given), normalised by a power of two and times
 * the kernel: the constant c0[ch], the eigenvalues lam[3 ch + i] of A ascending, their gaps d to the first and
 * the weights a = (V^T g)_i^2 / 4. Returns 1 when some channel is below 2^SKYSH_DERING_SUBNORMAL (C only). */
SKYSH_FN int skysh_dering_spectrum(SKYSH_DERING_COEFFS(c), SKYSH_IN SKYSH_DREAL tab[SKYSH_DERING_ROWS * SKYSH_DERING_BANDS],
                                   int row, SKYSH_OUT SKYSH_DREAL c0[3], SKYSH_OUT SKYSH_DREAL lam[9],
                                   SKYSH_OUT SKYSH_DREAL d[9], SKYSH_OUT SKYSH_DREAL a[9])
{
  SKYSH_CONST SKYSH_DREAL KER[SKYSH_DERING_COUNT] = SKYSH_ARRAY(SKYSH_DREAL, SKYSH_DERING_COUNT) SKYSH_DERING_KERNEL SKYSH_END;
  int tiny = 0;
  for (int ch = 0; ch < 3; ch++) {
    SKYSH_DREAL w[SKYSH_DERING_COUNT];
    SKYSH_DREAL m = 0.0;
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
      for (int k = l * l; k < (l + 1) * (l + 1); k++) {
        w[k] = SKYSH_DC(c, k, ch) * tab[row * SKYSH_DERING_BANDS + l];
        m = SKYSH_MAX(m, SKYSH_ABS(w[k]));
      }
    }
    SKYSH_DREAL f[9];
    for (int k = 0; k < 9; k++) { f[k] = 0.0; }
#if SKYSH_SHADER /* f = w / 2^e times the kernel, e the exponent of max |w| (shaders: a power of two near it; */
    /* m at least float's least normal, 2^-126: 2^-e at most 2^125, finite; a GPU flushes smaller values to 0) */
    SKYSH_DREAL inv = exp2(-floor(log2(SKYSH_MAX(m, SKYSH_DERING_NORMAL))) - 1.0);
    for (int k = 0; k < SKYSH_DERING_USED; k++) { f[k] = w[k] * inv * KER[k]; }
#else
    int e = 0;
    frexp(m, &e);
    if (m > 0.0 && e <= SKYSH_DERING_SUBNORMAL) { tiny = 1; }
    for (int k = 0; k < SKYSH_DERING_USED; k++) { f[k] = ldexp(w[k], -e) * KER[k]; }
#endif
    if (m == 0.0) { f[0] = KER[0]; } /* a zero channel: the constant 1, whose minimum passes as 0 does */
    c0[ch] = SKYSH_Y00 * f[0];
    SKYSH_DREAL g[3];
    g[0] = -SKYSH_K_LINEAR * f[3]; g[1] = -SKYSH_K_LINEAR * f[1]; g[2] = SKYSH_K_LINEAR * f[2];
    SKYSH_DREAL A[9];
    A[0] = SKYSH_K_SECTORAL * f[8] - SKYSH_K_ZONAL * f[6]; A[4] = -SKYSH_K_ZONAL * f[6] - SKYSH_K_SECTORAL * f[8];
    A[8] = 2.0 * SKYSH_K_ZONAL * f[6];
    A[1] = 0.5 * SKYSH_K_PRODUCT * f[4]; A[3] = A[1]; A[2] = -0.5 * SKYSH_K_PRODUCT * f[7]; A[6] = A[2];
    A[5] = -0.5 * SKYSH_K_PRODUCT * f[5]; A[7] = A[5];
    SKYSH_DREAL V[9];
    for (int k = 0; k < 9; k++) { V[k] = (k % 4 == 0) ? 1.0 : 0.0; }
    for (int sweep = 0; sweep < 8; sweep++) {
      for (int pair = 0; pair < 3; pair++) {
        int p = (pair == 2) ? 1 : 0;
        int q = (pair == 0) ? 1 : 2;
        SKYSH_DREAL apq = A[p * 3 + q];
        if (apq != 0.0) {
          SKYSH_DREAL theta = (A[q * 3 + q] - A[p * 3 + p]) / (2.0 * apq);
          SKYSH_DREAL t = ((theta >= 0.0) ? 1.0 : -1.0) / (SKYSH_ABS(theta) + SKYSH_SQRT(theta * theta + 1.0));
          SKYSH_DREAL cs = 1.0 / SKYSH_SQRT(t * t + 1.0);
          SKYSH_DREAL sn = t * cs;
          for (int k = 0; k < 3; k++) {
            SKYSH_DREAL akp = A[k * 3 + p]; SKYSH_DREAL akq = A[k * 3 + q];
            SKYSH_DREAL vkp = V[k * 3 + p]; SKYSH_DREAL vkq = V[k * 3 + q];
            A[k * 3 + p] = cs * akp - sn * akq; A[k * 3 + q] = sn * akp + cs * akq;
            V[k * 3 + p] = cs * vkp - sn * vkq; V[k * 3 + q] = sn * vkp + cs * vkq;
          }
          for (int k = 0; k < 3; k++) {
            SKYSH_DREAL apk = A[p * 3 + k]; SKYSH_DREAL aqk = A[q * 3 + k];
            A[p * 3 + k] = cs * apk - sn * aqk; A[q * 3 + k] = sn * apk + cs * aqk;
          }
        }
      }
    }
    for (int i = 0; i < 3; i++) {
      lam[3 * ch + i] = A[i * 4];
      SKYSH_DREAL gam = V[i] * g[0] + V[3 + i] * g[1] + V[6 + i] * g[2];
      a[3 * ch + i] = 0.25 * gam * gam;
    }
    for (int i = 0; i < 2; i++) { /* the eigenvalues ascending, their weights with them */
      for (int j = 3 * ch; j < 3 * ch + 2 - i; j++) {
        if (lam[j] > lam[j + 1]) {
          SKYSH_DREAL tl = lam[j]; lam[j] = lam[j + 1]; lam[j + 1] = tl;
          SKYSH_DREAL ta = a[j]; a[j] = a[j + 1]; a[j + 1] = ta;
        }
      }
    }
    for (int i = 0; i < 3; i++) { d[3 * ch + i] = lam[3 * ch + i] - lam[3 * ch]; }
  }
  return tiny;
}

/* The least over the channels of the certified minimum with the window (1, s1, s2), less SKYSH_DERING_ROUND:
 * the window passes where it is >= 0 (skysh.post.dering._dual3). */
SKYSH_FN SKYSH_DREAL skysh_dering_dual(SKYSH_IN SKYSH_DREAL c0[3], SKYSH_IN SKYSH_DREAL lam[9], SKYSH_IN SKYSH_DREAL dd[9],
                                       SKYSH_IN SKYSH_DREAL aa[9], SKYSH_DREAL s1, SKYSH_DREAL s2)
{
  SKYSH_DREAL least = 1.0e30;
  for (int ch = 0; ch < 3; ch++) {
    SKYSH_DREAL d[3];
    SKYSH_DREAL ar[3];
    SKYSH_DREAL x = SKYSH_DERING_FLOOR;
    SKYSH_DREAL cum = 0.0;
    for (int i = 0; i < 3; i++) {
      d[i] = dd[3 * ch + i] * s2; ar[i] = aa[3 * ch + i] * (s1 * s1); cum += ar[i];
      x = SKYSH_MAX(x, SKYSH_SQRT(cum) - d[i]);
    }
    SKYSH_DREAL low = x;
    for (int it = 0; it <= SKYSH_DERING_STEPS; it++) {
      SKYSH_DREAL s = 0.0;
      SKYSH_DREAL tt = 0.0;
      for (int i = 0; i < 3; i++) {
        SKYSH_DREAL w = 1.0 / (d[i] + x);
        SKYSH_DREAL aw2 = ar[i] * w * w;
        s += aw2; tt += aw2 * w;
      }
      x = SKYSH_MAX(x + (SKYSH_SQRT(s) - 1.0) * s / (tt + SKYSH_DERING_TINY), low);
      if (it == 0) { /* the proven bounds of the clusters of eigenvalues */
        SKYSH_DREAL big = 0.0;
        for (int k = 1; k < 3; k++) {
          big += ar[k - 1];
          SKYSH_DREAL c0s = 0.0;
          SKYSH_DREAL t0s = 0.0;
          for (int i = k; i < 3; i++) {
            SKYSH_DREAL far = SKYSH_MAX(d[i] - d[k - 1], SKYSH_DERING_POLE);
            SKYSH_DREAL u = ar[i] / (far * far);
            c0s += u; t0s += u / far;
          }
          t0s += SKYSH_DERING_TINY;
          SKYSH_DREAL cub = big / (4.0 * t0s);
          SKYSH_DREAL near = SKYSH_MIN(SKYSH_SQRT(big / (2.0 * SKYSH_MAX(1.0 - c0s, 0.0) + SKYSH_DERING_TINY)), SKYSH_CBRT(cub));
          x = SKYSH_MAX(x, SKYSH_MAX((SKYSH_SQRT(c0s) - 1.0) * c0s / t0s, near) - d[k - 1]);
        }
        low = x;
      }
    }
    SKYSH_DREAL sum = 0.0;
    for (int i = 0; i < 3; i++) { sum += ar[i] / (d[i] + x); }
    least = SKYSH_MIN(least, c0[ch] + lam[3 * ch] * s2 - x - sum);
  }
  return least - SKYSH_DERING_ROUND;
}

/* Band 1's (j = 1) or band 2's (j = 2) factor in row r of tab, 0 past the bands (the target's s1, s2). */
SKYSH_FN SKYSH_DREAL skysh_dering_factor(SKYSH_IN SKYSH_DREAL tab[SKYSH_DERING_ROWS * SKYSH_DERING_BANDS], int r, int j)
{
  return j < SKYSH_DERING_BANDS ? tab[r * SKYSH_DERING_BANDS + SKYSH_MIN_INT(j, SKYSH_DERING_BANDS - 1)] : 0.0;
}

SKYSH_FN int SKYSH_DERING_NAME(SKYSH_INOUT SKYSH_DERING_COEFFS(c), SKYSH_OUT SKYSH_DREAL scales_out[SKYSH_DERING_BANDS],
                               SKYSH_OUT SKYSH_DREAL position_out[1])
{
  SKYSH_CONST SKYSH_DREAL TAB[SKYSH_DERING_ROWS * SKYSH_DERING_BANDS] =
      SKYSH_ARRAY(SKYSH_DREAL, SKYSH_DERING_ROWS * SKYSH_DERING_BANDS) SKYSH_DERING_TABLE SKYSH_END;
#if !SKYSH_SHADER /* the precondition: a NaN or an inf fails at once, c untouched */
  int finite = 1;
  for (int k = 0; k < SKYSH_DERING_COUNT; k++) { for (int ch = 0; ch < 3; ch++) { finite = finite && isfinite(c[k][ch]); } }
  if (!finite) {
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) { scales_out[l] = 1.0; }
    position_out[0] = 0.0;
    return 1;
  }
#endif
  SKYSH_DREAL c0[3];
  SKYSH_DREAL lam[9];
  SKYSH_DREAL d[9];
  SKYSH_DREAL a[9];
  int row = SKYSH_DERING_ROWS;
  SKYSH_DREAL position = 0.0;
  if (skysh_dering_spectrum(c, TAB, 0, c0, lam, d, a) == 1) { /* subnormal (C only): whole rows, as rounded */
    for (int r = 0; r < SKYSH_DERING_ROWS && row == SKYSH_DERING_ROWS; r++) {
      skysh_dering_spectrum(c, TAB, r, c0, lam, d, a);
      if (skysh_dering_dual(c0, lam, d, a, 1.0, 1.0) >= 0.0) { row = r; }
    }
    position = SKYSH_TO_DREAL(row == SKYSH_DERING_ROWS ? SKYSH_DERING_ROWS - 1 : row);
  } else {
    for (int r = 0; r < SKYSH_DERING_ROWS && row == SKYSH_DERING_ROWS; r++) {
      if (skysh_dering_dual(c0, lam, d, a, skysh_dering_factor(TAB, r, 1), skysh_dering_factor(TAB, r, 2)) >= 0.0) { row = r; }
    }
    position = SKYSH_TO_DREAL(row == SKYSH_DERING_ROWS ? SKYSH_DERING_ROWS - 1 : row);
    if (row > 0 && row < SKYSH_DERING_ROWS) { /* the least passing fraction of the step from row - 1 */
      SKYSH_DREAL s1 = skysh_dering_factor(TAB, row - 1, 1);
      SKYSH_DREAL s2 = skysh_dering_factor(TAB, row - 1, 2);
      SKYSH_DREAL ds1 = skysh_dering_factor(TAB, row, 1) - s1;
      SKYSH_DREAL ds2 = skysh_dering_factor(TAB, row, 2) - s2;
      SKYSH_DREAL m0 = skysh_dering_dual(c0, lam, d, a, s1, s2);
      SKYSH_DREAL m1 = skysh_dering_dual(c0, lam, d, a, s1 + ds1, s2 + ds2);
      SKYSH_DREAL guess = m0 / SKYSH_MIN(m0 - m1, -SKYSH_DERING_TINY);
      SKYSH_DREAL lo = 0.0;
      SKYSH_DREAL hi = 1.0;
      SKYSH_DREAL cand = SKYSH_MIN(SKYSH_MAX(ceil(guess * SKYSH_DERING_LATTICE), 1.0), SKYSH_DERING_LATTICE) / SKYSH_DERING_LATTICE;
      for (int it = 0; it < 2 * SKYSH_DERING_HALVINGS && hi - lo > 1.0 / SKYSH_DERING_LATTICE; it++) {
        if (skysh_dering_dual(c0, lam, d, a, s1 + cand * ds1, s2 + cand * ds2) >= 0.0) { hi = cand; } else { lo = cand; }
        cand = floor(0.5 * (lo + hi) * SKYSH_DERING_LATTICE) / SKYSH_DERING_LATTICE;
      }
      position = SKYSH_TO_DREAL(row - 1) + hi;
    }
  }
  int i = SKYSH_MIN_INT(SKYSH_TO_INT(position), SKYSH_DERING_ROWS - 1); /* the factors at the position */
  int j = SKYSH_MIN_INT(i + 1, SKYSH_DERING_ROWS - 1); /* a whole position is its row exactly */
  SKYSH_DREAL frac = position - SKYSH_TO_DREAL(i);
  for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
    SKYSH_DREAL low = TAB[i * SKYSH_DERING_BANDS + l];
    scales_out[l] = low + frac * (TAB[j * SKYSH_DERING_BANDS + l] - low);
    for (int k = l * l; k < (l + 1) * (l + 1); k++) {
      for (int ch = 0; ch < 3; ch++) { SKYSH_DC(c, k, ch) = SKYSH_DC(c, k, ch) * scales_out[l]; }
    }
  }
  position_out[0] = position;
  return row == SKYSH_DERING_ROWS ? 1 : 0;
}
