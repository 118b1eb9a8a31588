/*
 * Deringing of RGB radiance SH of 5 to 7 bands (and 4-band radiance) in C
 * (skysh/export/templates/c_like_dering_certificate_c.h), as skysh.post.dering.dering does it (method
 * "window"): the least window position along SKYSH_DERING_TABLE (SKYSH_DERING_ROWS rows of
 * SKYSH_DERING_BANDS per-band factors, row-major), the factors linear between neighbouring rows, whose
 * windowed target (SKYSH_DERING_KERNEL times the coefficients) is certified non-negative in all three
 * channels by the sampling certificate of skysh.sh.minimum.certified_min with thr = 0:
 *
 *  - level 0: the target at SKYSH_DERING_DIRECTIONS Fibonacci directions (their covering radius at most
 *    SKYSH_DERING_COVER rad); a negative value refutes the window; a channel whose least value less
 *    K r^2 / 2 (r = SKYSH_DERING_COVER, K the Bernstein bound of |f''| along great circles, sum_l l^2
 *    |f_l|_2 SKYSH_DERING_BAND_NORM[l], and the sampling allowance SKYSH_DERING_SAMPLE_ROUNDING times
 *    sum_l |f_l|_2 SKYSH_DERING_BAND_NORM[l]) is non-negative passes;
 *  - else each direction whose value less that slack is negative is a cell (the square [-h, h]^2 of its
 *    tangent plane under the exponential map, h = SKYSH_DERING_COVER), split into SKYSH_DERING_SPLIT^2
 *    sub-squares SKYSH_DERING_LEVELS times while its centre's value less K h^2 (h: its half side) is
 *    negative; the channel passes when no cell is left. It fails at a negative sampled value, with more
 *    than SKYSH_DERING_BUDGET cells (the budget), or with cells left and the least sampled value below
 *    the last level's slack K (SKYSH_DERING_COVER / SPLIT^LEVELS)^2 plus the allowance (hopeless).
 *
 * The search (skysh.post.dering.least_window): the least whole row r that passes; none: the last row,
 * failed; r = 0: position 0; else the least fraction k / SKYSH_DERING_LATTICE of the step from row r - 1
 * that passes, the level-0 values at fraction f taken as v_lo + f (v_hi - v_lo) of rows r - 1 and r, by
 * galloping up from the largest zero of the level-0 values less the last level's slack (below it no
 * certificate passes), then bisection on multiples of 1 / LATTICE. A function with a channel below
 * 2^SKYSH_DERING_SUBNORMAL in every coefficient keeps whole rows, decided on its windowed coefficients as
 * rounded. SKYSH_DERING_NAME(c, scales_out, position_out): as c_like_dering3.h's (c[SKYSH_DERING_COUNT][3]),
 * precondition included: every coefficient finite, else it returns 1 at once, c untouched (scales_out 1,
 * position 0). Its cost per call: skysh.export.dering.CERTIFICATE_COST (python
 * tests/export/test_export_dering_certificate.py prints it).
 *
 * Storage, no allocation: the grid (directions, tangent frames and the basis at them, SKYSH_DERING_DIRECTIONS
 * x (9 + SKYSH_DERING_COUNT) doubles, 1.9 MB at 7 bands) is built at the first call into a function-local
 * static array and only read after; the scratch (two rows of level-0 values and the cells, 0.4 MB) is
 * SKYSH_DERING_STORAGE, static unless defined before this file. The function is therefore not reentrant:
 * call it from one thread at a time, or define SKYSH_DERING_STORAGE as static _Thread_local (C11) or
 * static thread_local (C++11) and make the first call from one thread. SKYSH_DERING_TALLY(n), if defined,
 * is called with the number of SH evaluations (function and direction) as they are made (a benchmark's hook).
 */
#ifndef SKYSH_DERING_STORAGE
#define SKYSH_DERING_STORAGE static
#endif
#ifndef SKYSH_DERING_TALLY
#define SKYSH_DERING_TALLY(n) ((void)0)
#endif
#define SKYSH_DERING_M SKYSH_DERING_DIRECTIONS
#define SKYSH_DERING_CELLS (SKYSH_DERING_SPLIT * SKYSH_DERING_SPLIT * (SKYSH_DERING_BUDGET + 1))

/* The real SH basis at the unit vector (x, y, z) (skysh.sh.basis: the associated-Legendre recurrence in l). */
static inline void skysh_dering_basis(double x, double y, double z, double *out)
{
  static const double DIAG[SKYSH_DERING_BANDS] = {SKYSH_DERING_DIAG};
  static const double NEXT[SKYSH_DERING_BANDS] = {SKYSH_DERING_NEXT};
  static const double RA[SKYSH_DERING_BANDS * SKYSH_DERING_BANDS] = {SKYSH_DERING_RA};
  static const double RB[SKYSH_DERING_BANDS * SKYSH_DERING_BANDS] = {SKYSH_DERING_RB};
  double cm[SKYSH_DERING_BANDS], sm[SKYSH_DERING_BANDS], q[3][SKYSH_DERING_BANDS];
  cm[0] = 1.0; sm[0] = 0.0;
  for (int m = 1; m < SKYSH_DERING_BANDS; m++) {
    cm[m] = x * cm[m - 1] - y * sm[m - 1];
    sm[m] = x * sm[m - 1] + y * cm[m - 1];
  }
  for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
    double *ql = q[l % 3];
    const double *q1 = q[(l + 2) % 3], *q2 = q[(l + 1) % 3];
    for (int m = 0; m + 1 < l; m++) { ql[m] = q1[m] * z * RA[l * SKYSH_DERING_BANDS + m] - q2[m] * RB[l * SKYSH_DERING_BANDS + m]; }
    if (l >= 1) { ql[l - 1] = z * NEXT[l]; }
    ql[l] = DIAG[l];
    int centre = l * l + l;
    out[centre] = ql[0];
    for (int m = 1; m <= l; m++) { out[centre + m] = ql[m] * cm[m]; out[centre - m] = ql[m] * sm[m]; }
  }
}

/* The grid, built at the first call: per direction j, grid[9 j ..] its unit vector and tangent frame (Duff et
 * al. 2017), then grid[9 M + k M + j] basis function k at it (the basis K x M, as skysh.sh.minimum's). */
static inline const double *skysh_dering_grid(void)
{
  static double grid[SKYSH_DERING_M * (9 + SKYSH_DERING_COUNT)];
  static int built = 0;
  if (!built) {
    double y[SKYSH_DERING_COUNT];
    for (int j = 0; j < SKYSH_DERING_M; j++) {
      double i = j + 0.5;
      double z = 1.0 - 2.0 * i / SKYSH_DERING_M;
      double phi = i * SKYSH_DERING_PI * SKYSH_DERING_GOLDEN;
      double s = sqrt(fmax(0.0, 1.0 - z * z));
      double *g = grid + 9 * j;
      g[0] = s * cos(phi); g[1] = s * sin(phi); g[2] = z;
      double sign = copysign(1.0, z), a = -1.0 / (sign + z), b = g[0] * g[1] * a;
      g[3] = 1.0 + sign * g[0] * g[0] * a; g[4] = sign * b; g[5] = -sign * g[0];
      g[6] = b; g[7] = sign + g[1] * g[1] * a; g[8] = -g[1];
      skysh_dering_basis(g[0], g[1], g[2], y);
      for (int k = 0; k < SKYSH_DERING_COUNT; k++) { grid[9 * SKYSH_DERING_M + k * SKYSH_DERING_M + j] = y[k]; }
    }
    built = 1;
  }
  return grid;
}

/* The curvature bound K of f (skysh.sh.minimum.curvature), and in allow[0] its sampling allowance. */
static inline double skysh_dering_curvature(const double *f, double allow[1])
{
  static const double NORM[SKYSH_DERING_BANDS] = {SKYSH_DERING_BAND_NORM};
  double k2 = 0.0, sum = 0.0;
  for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
    double s = 0.0;
    for (int k = l * l; k < (l + 1) * (l + 1); k++) { s += f[k] * f[k]; }
    double norm = sqrt(s) * NORM[l];
    k2 += norm * (double)(l * l); sum += norm;
  }
  allow[0] = SKYSH_DERING_SAMPLE_ROUNDING * sum;
  return k2;
}

/* The level-0 values of channel ch at fraction f between the rows' values lo and hi (hi = lo, f = 0: a row's). */
static inline double skysh_dering_level0(const double *lo, const double *hi, double f, int j)
{
  return f == 0.0 ? lo[j] : lo[j] + f * (hi[j] - lo[j]);
}

/* Whether the certificate puts the target f (normalised, windowed, times the kernel) at >= 0, given its level-0
 * values (lo, hi, frac), its least sampled value best (>= 0), its K and allowance: the refinement. */
static inline int skysh_dering_certify(const double *f, const double *lo, const double *hi, double frac, double best,
                                       double k2, double allow)
{
  SKYSH_DERING_STORAGE int root[SKYSH_DERING_CELLS];
  SKYSH_DERING_STORAGE double cu[SKYSH_DERING_CELLS], cv[SKYSH_DERING_CELLS], val[SKYSH_DERING_CELLS];
  const double *grid = skysh_dering_grid();
  const double slack0 = 0.5 * k2 * (SKYSH_DERING_COVER * SKYSH_DERING_COVER) + allow;
  int n = 0;
  for (int j = 0; j < SKYSH_DERING_M; j++) {
    if (skysh_dering_level0(lo, hi, frac, j) - slack0 < fmin(best, 0.0)) {
      if (n == SKYSH_DERING_BUDGET + 1) { return 0; } /* over the budget at the first level: frozen */
      root[n] = j; cu[n] = 0.0; cv[n] = 0.0; n++;
    }
  }
  const double hopeless = 0.0 + k2 * SKYSH_DERING_FINAL + allow;
  double half = SKYSH_DERING_COVER;
  for (int level = 0; level < SKYSH_DERING_LEVELS; level++) {
    if (n == 0) { return 1; }
    if (n > SKYSH_DERING_BUDGET || best < hopeless) { return 0; } /* frozen: its bound stays below 0 */
    for (int i = n - 1; i >= 0; i--) { /* the sub-squares of cell i, in place (4 i >= i) */
      for (int s = 0; s < SKYSH_DERING_SPLIT * SKYSH_DERING_SPLIT; s++) {
        int o = SKYSH_DERING_SPLIT * SKYSH_DERING_SPLIT * i + s;
        double ou = (2.0 * (s / SKYSH_DERING_SPLIT) + 1.0) / SKYSH_DERING_SPLIT - 1.0;
        double ov = (2.0 * (s % SKYSH_DERING_SPLIT) + 1.0) / SKYSH_DERING_SPLIT - 1.0;
        root[o] = root[i]; cu[o] = cu[i] + half * ou; cv[o] = cv[i] + half * ov;
      }
    }
    n *= SKYSH_DERING_SPLIT * SKYSH_DERING_SPLIT;
    half = half / SKYSH_DERING_SPLIT;
    for (int i = 0; i < n; i++) {
      const double *g = grid + 9 * root[i];
      double r = hypot(cu[i], cv[i]);
      double x = SKYSH_DERING_PI * (r == 0.0 ? 1.0e-20 : r / SKYSH_DERING_PI); /* numpy's sinc(r / pi) */
      double sinc = sin(x) / x, cr = cos(r), p[3], y[SKYSH_DERING_COUNT], v = 0.0;
      for (int e = 0; e < 3; e++) { p[e] = cr * g[e] + sinc * (cu[i] * g[3 + e] + cv[i] * g[6 + e]); }
      double norm = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      skysh_dering_basis(p[0] / norm, p[1] / norm, p[2] / norm, y);
      for (int k = 0; k < SKYSH_DERING_COUNT; k++) { v += f[k] * y[k]; }
      val[i] = v;
      best = fmin(best, v);
    }
    SKYSH_DERING_TALLY(n);
    if (best < 0.0) { return 0; } /* a negative value: refuted */
    int kept = 0;
    for (int i = 0; i < n; i++) {
      if (val[i] - k2 * half * half - allow < 0.0) { root[kept] = root[i]; cu[kept] = cu[i]; cv[kept] = cv[i]; kept++; }
    }
    n = kept;
  }
  return n == 0;
}

/* Whether every channel of the targets flat[3 K] with level-0 values (lo, hi, frac) (3 M each) is certified >= 0
 * (skysh.post.dering._passes): a negative level-0 value refutes; else the channels that level 0 leaves undecided
 * are refined. */
static inline int skysh_dering_passes(const double *flat, const double *lo, const double *hi, double frac)
{
  double best[3], k2[3], allow[3];
  int refuted = 0;
  for (int ch = 0; ch < 3; ch++) {
    best[ch] = skysh_dering_level0(lo + ch * SKYSH_DERING_M, hi + ch * SKYSH_DERING_M, frac, 0);
    for (int j = 1; j < SKYSH_DERING_M; j++) {
      best[ch] = fmin(best[ch], skysh_dering_level0(lo + ch * SKYSH_DERING_M, hi + ch * SKYSH_DERING_M, frac, j));
    }
    k2[ch] = skysh_dering_curvature(flat + ch * SKYSH_DERING_COUNT, allow + ch);
    refuted |= best[ch] < 0.0;
  }
  for (int ch = 0; ch < 3 && !refuted; ch++) {
    if (best[ch] - 0.5 * k2[ch] * (SKYSH_DERING_COVER * SKYSH_DERING_COVER) - allow[ch] < 0.0
        && !skysh_dering_certify(flat + ch * SKYSH_DERING_COUNT, lo + ch * SKYSH_DERING_M, hi + ch * SKYSH_DERING_M,
                                 frac, best[ch], k2[ch], allow[ch])) {
      return 0;
    }
  }
  return !refuted;
}

/* t (3 K: each channel of c windowed by row `row`, divided by a power of two) times the kernel and the factors of
 * rows lo and hi at fraction f (hi = lo: a row's), into flat, and its level-0 values into vals when vals is not
 * null. Returns 1 when some channel is below 2^SKYSH_DERING_SUBNORMAL. */
static inline int skysh_dering_target(double c[SKYSH_DERING_COUNT][3], int row, int lo, int hi, double f, double *flat,
                                      double *vals)
{
  static const double TAB[SKYSH_DERING_ROWS * SKYSH_DERING_BANDS] = {SKYSH_DERING_TABLE};
  static const double KER[SKYSH_DERING_COUNT] = {SKYSH_DERING_KERNEL};
  int tiny = 0;
  for (int ch = 0; ch < 3; ch++) {
    double w[SKYSH_DERING_COUNT], m = 0.0;
    int e = 0;
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
      for (int k = l * l; k < (l + 1) * (l + 1); k++) { w[k] = c[k][ch] * TAB[row * SKYSH_DERING_BANDS + l]; m = fmax(m, fabs(w[k])); }
    }
    frexp(m, &e);
    tiny |= m > 0.0 && e <= SKYSH_DERING_SUBNORMAL;
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) {
      for (int k = l * l; k < (l + 1) * (l + 1); k++) {
        double t = m == 0.0 ? (k == 0 ? 1.0 : 0.0) : ldexp(w[k], -e);
        double plo = KER[k] * TAB[lo * SKYSH_DERING_BANDS + l], phi = KER[k] * TAB[hi * SKYSH_DERING_BANDS + l];
        flat[ch * SKYSH_DERING_COUNT + k] = t * (f == 0.0 ? plo : plo + f * (phi - plo));
      }
    }
  }
  if (vals) {
    const double *basis = skysh_dering_grid() + 9 * SKYSH_DERING_M;
    for (int ch = 0; ch < 3; ch++) {
      double *v = vals + ch * SKYSH_DERING_M;
      for (int j = 0; j < SKYSH_DERING_M; j++) { v[j] = 0.0; }
      for (int k = 0; k < SKYSH_DERING_COUNT; k++) {
        const double fk = flat[ch * SKYSH_DERING_COUNT + k], *y = basis + k * SKYSH_DERING_M;
        for (int j = 0; j < SKYSH_DERING_M; j++) { v[j] += fk * y[j]; }
      }
    }
    SKYSH_DERING_TALLY(3 * SKYSH_DERING_M);
  }
  return tiny;
}

/* The least passing fraction of the step from row - 1 to row (skysh.post.dering._fraction, certified): the start
 * where every level-0 value reaches the last level's slack (each side linear in f), then _bisect's gallop. */
static inline double skysh_dering_fraction(double c[SKYSH_DERING_COUNT][3], int row, const double *vlo, const double *vhi)
{
  double flo[3 * SKYSH_DERING_COUNT], fhi[3 * SKYSH_DERING_COUNT], flat[3 * SKYSH_DERING_COUNT], start = 0.0;
  skysh_dering_target(c, 0, row - 1, row, 0.0, flo, (double *)0);
  skysh_dering_target(c, 0, row - 1, row, 1.0, fhi, (double *)0);
  for (int ch = 0; ch < 3; ch++) {
    double alo, ahi;
    double klo = skysh_dering_curvature(flo + ch * SKYSH_DERING_COUNT, &alo);
    double khi = skysh_dering_curvature(fhi + ch * SKYSH_DERING_COUNT, &ahi);
    double olo = klo * SKYSH_DERING_FINAL + alo, ohi = khi * SKYSH_DERING_FINAL + ahi;
    for (int j = ch * SKYSH_DERING_M; j < (ch + 1) * SKYSH_DERING_M; j++) {
      double glo = vlo[j] - olo, ghi = vhi[j] - ohi;
      if (glo < 0.0) { start = fmax(start, glo / fmin(glo - ghi, -SKYSH_DERING_TINY)); }
    }
  }
  const double q = SKYSH_DERING_LATTICE;
  double lo = floor(fmin(start, 1.0) * q) / q, hi = 1.0, step = 1.0;
  double cand = fmin(fmax(ceil((lo + 1.0 / q) * q), lo * q + 1.0), q) / q;
  int go = 1, down = 0, fresh = 1;
  for (int it = 0; it < 8 * SKYSH_DERING_HALVINGS && hi - lo > 1.0 / q; it++) {
    skysh_dering_target(c, 0, row - 1, row, cand, flat, (double *)0);
    int ok = skysh_dering_passes(flat, vlo, vhi, cand);
    if (ok) { hi = cand; } else { lo = cand; }
    if (fresh) { down = ok; }
    go = go && (fresh || ok == down);
    fresh = 0;
    double next = down ? hi - step / q : lo + step / q;
    go = go && next > lo && next < hi;
    step = go ? 2.0 * step : step;
    cand = go ? next : floor(0.5 * (lo + hi) * q) / q;
  }
  return hi;
}

static inline int SKYSH_DERING_NAME(double c[SKYSH_DERING_COUNT][3], double scales_out[SKYSH_DERING_BANDS],
                                    double position_out[1])
{
  static const double TAB[SKYSH_DERING_ROWS * SKYSH_DERING_BANDS] = {SKYSH_DERING_TABLE};
  /* the precondition: a NaN or an inf fails at once, c untouched */
  int finite = 1;
  for (int k = 0; k < SKYSH_DERING_COUNT; k++) { for (int ch = 0; ch < 3; ch++) { finite = finite && isfinite(c[k][ch]); } }
  if (!finite) {
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) { scales_out[l] = 1.0; }
    position_out[0] = 0.0;
    return 1;
  }
  SKYSH_DERING_STORAGE double vals[2][3 * SKYSH_DERING_M];
  double flat[3 * SKYSH_DERING_COUNT], position = 0.0;
  int row = SKYSH_DERING_ROWS;
  int tiny = skysh_dering_target(c, 0, 0, 0, 0.0, flat, (double *)0);
  for (int r = 0; r < SKYSH_DERING_ROWS && row == SKYSH_DERING_ROWS; r++) {
    skysh_dering_target(c, tiny ? r : 0, tiny ? 0 : r, tiny ? 0 : r, 0.0, flat, vals[r % 2]);
    if (skysh_dering_passes(flat, vals[r % 2], vals[r % 2], 0.0)) { row = r; }
  }
  position = (double)(row == SKYSH_DERING_ROWS ? SKYSH_DERING_ROWS - 1 : row);
  if (!tiny && row > 0 && row < SKYSH_DERING_ROWS) {
    position = (double)(row - 1) + skysh_dering_fraction(c, row, vals[(row - 1) % 2], vals[row % 2]);
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
