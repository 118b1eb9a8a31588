/*
 * Deringing of 3-band RGB radiance SH for C, GLSL and HLSL (skysh/export/templates/c_like_dering3.h),
 * as skysh.post.dering.dering does it: the least row of the window table (SKYSH_DERING_TAB1,
 * SKYSH_DERING_TAB2: the factors of bands 1 and 2) whose windowed target (the kernel
 * SKYSH_DERING_KERNEL times the coefficients: irradiance or radiance) is non-negative in all three
 * channels. Each row's exact minimum over the sphere (skysh.sh.minimum) is the minimum of
 * c0 + g.u + u.A u over unit u: the eigenvalues of A by cyclic Jacobi rotations, then the secular
 * equation's root by the proven start, one Newton step, the proven cluster bounds and
 * SKYSH_DERING_STEPS more steps; a row passes when that minimum is at least SKYSH_DERING_ROUND.
 *
 * SKYSH_DERING_NAME(c, scales_out) windows c in place with that row (the last one when none
 * passes), writes the row's band factors (1, tab1, tab2) to scales_out and returns 1 when no row
 * passes, else 0. C (64-bit reals whatever skysh_real is): c[9][3], c[k][channel], and scales_out[3];
 * GLSL and HLSL (float): inout c[27], c[3 k + channel], and out scales_out[3].
 * The numbers (the table, the kernel, the basis constants SKYSH_Y00, SKYSH_K_LINEAR, SKYSH_K_PRODUCT,
 * SKYSH_K_ZONAL, SKYSH_K_SECTORAL, the guards SKYSH_DERING_TINY, SKYSH_DERING_FLOOR,
 * SKYSH_DERING_POLE) are #defines written before this file (skysh.export.dering).
 */
SKYSH_FN int SKYSH_DERING_NAME(SKYSH_INOUT SKYSH_DERING_COEFFS(c), SKYSH_OUT SKYSH_DREAL scales_out[3])
{
  SKYSH_CONST SKYSH_DREAL TAB1[SKYSH_DERING_ROWS] = SKYSH_ARRAY(SKYSH_DREAL, SKYSH_DERING_ROWS) SKYSH_DERING_TAB1 SKYSH_END;
  SKYSH_CONST SKYSH_DREAL TAB2[SKYSH_DERING_ROWS] = SKYSH_ARRAY(SKYSH_DREAL, SKYSH_DERING_ROWS) SKYSH_DERING_TAB2 SKYSH_END;
  SKYSH_CONST SKYSH_DREAL KER[9] = SKYSH_ARRAY(SKYSH_DREAL, 9) SKYSH_DERING_KERNEL SKYSH_END;
  int passed[SKYSH_DERING_ROWS];
  for (int r = 0; r < SKYSH_DERING_ROWS; r++) { passed[r] = 1; }
  for (int ch = 0; ch < 3; ch++) {
    SKYSH_DREAL m = 0.0;
    for (int k = 0; k < 9; k++) { m = SKYSH_MAX(m, SKYSH_ABS(SKYSH_DC(c, k, ch))); }
    if (m > 0.0) {
      SKYSH_DREAL f[9];
#if SKYSH_SHADER /* f = c / 2^e times the kernel, e the exponent of max |c| (shaders: a power of two near it) */
      SKYSH_DREAL inv = exp2(-floor(log2(m)) - 1.0);
      for (int k = 0; k < 9; k++) { f[k] = SKYSH_DC(c, k, ch) * inv * KER[k]; }
#else
      int e; frexp(m, &e);
      for (int k = 0; k < 9; k++) { f[k] = ldexp(SKYSH_DC(c, k, ch), -e) * KER[k]; }
#endif
      SKYSH_DREAL c0 = SKYSH_Y00 * f[0];
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
      SKYSH_DREAL lam[3];
      SKYSH_DREAL a[3];
      for (int i = 0; i < 3; i++) {
        lam[i] = A[i * 4];
        SKYSH_DREAL gam = V[i] * g[0] + V[3 + i] * g[1] + V[6 + i] * g[2];
        a[i] = 0.25 * gam * gam;
      }
      for (int i = 0; i < 2; i++) { /* the eigenvalues ascending, their weights with them */
        for (int j = 0; j < 2 - i; j++) {
          if (lam[j] > lam[j + 1]) {
            SKYSH_DREAL tl = lam[j]; lam[j] = lam[j + 1]; lam[j + 1] = tl;
            SKYSH_DREAL ta = a[j]; a[j] = a[j + 1]; a[j + 1] = ta;
          }
        }
      }
      for (int r = 0; r < SKYSH_DERING_ROWS; r++) {
        SKYSH_DREAL s1 = TAB1[r];
        SKYSH_DREAL s2 = TAB2[r];
        SKYSH_DREAL d[3];
        SKYSH_DREAL ar[3];
        SKYSH_DREAL x = SKYSH_DERING_FLOOR;
        SKYSH_DREAL cum = 0.0;
        for (int i = 0; i < 3; i++) {
          d[i] = s2 * lam[i] - s2 * lam[0]; ar[i] = a[i] * (s1 * s1); cum += ar[i]; x = SKYSH_MAX(x, SKYSH_SQRT(cum) - d[i]);
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
        if (c0 + s2 * lam[0] - x - sum < SKYSH_DERING_ROUND) { passed[r] = 0; }
      }
    }
  }
  int row = SKYSH_DERING_ROWS - 1;
  int failed = 1;
  for (int r = SKYSH_DERING_ROWS - 1; r >= 0; r--) { if (passed[r] == 1) { row = r; failed = 0; } }
  scales_out[0] = 1.0; scales_out[1] = TAB1[row]; scales_out[2] = TAB2[row];
  for (int k = 0; k < 9; k++) {
    SKYSH_DREAL s = (k == 0) ? 1.0 : ((k < 4) ? TAB1[row] : TAB2[row]);
    for (int ch = 0; ch < 3; ch++) { SKYSH_DC(c, k, ch) = SKYSH_DC(c, k, ch) * s; }
  }
  return failed;
}
