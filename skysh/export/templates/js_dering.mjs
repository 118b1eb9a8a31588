// ---------------------------------------------------------------------------------------------------------------
// Deringing (Sloan 2017) at every band count, as skysh.post.dering.dering (target irradiance, the least window):
// the least row of the band count's window table whose irradiance is non-negative in every channel, then the least
// fraction k / LATTICE of the step from the row before it whose window passes (LATTICE = 1 / tolerance(n)), the
// factors linear per band between the rows; the last row (failed) when none passes. Each channel is first divided
// by a power of two (exact). 1..4 bands (A_3 = 0: a 3-band target) decide on the exact minimum of the quadratic part
// (cyclic Jacobi rotations, one eigendecomposition per channel for every window; the dual's proven start, one Newton
// step, the cluster bounds, the remaining steps), and their fraction by bisection of [0, 1] on multiples of
// 1 / 1024 (the minimum is concave in the fraction: the passing fractions form one interval ending at 1). 5..7
// bands decide on skysh.sh.minimum.certified_min's certificate with thr = 0 (below), whose passing fractions need
// not form an interval (its cell budget, its slack): there the search is Python's, candidate for candidate
// (certifiedFraction). A function with a channel below 2^SUBNORMAL keeps whole rows, decided on its windowed
// coefficients as rounded. The coefficients are finite: coefficients() checks its inputs (a NaN would pass through
// Math.max as no value), so the deringing does not check them again.
// ---------------------------------------------------------------------------------------------------------------
const DERING = DATA.dering;
const DR_ROWS = DERING.rows;
const DR_LATTICE = DERING.lattice; // per band count: 1 / skysh.post.dering.tolerance(n)
const DR_EXACT = DERING.exact; // per band count: skysh.post.dering.exact_target(n), else the certificate decides
const DR_KERNEL = new Float64Array(DERING.kernel);
const DR_TABLES = DERING.windows.map((rows) => new Float64Array(rows)); // [n - 1][r n + l]: window_table(n)
const DR_TARGET = DR_TABLES.map((rows, i) => rows.map((s, k) => s * DR_KERNEL[k % (i + 1)])); // rows times A_l
const SUBNORMAL = DERING.subnormal; // skysh.post.dering.SUBNORMAL_EXPONENT: a channel whose frexp exponent is at most this is subnormal
const DR_K = MAX_BANDS * MAX_BANDS;
const DR_T = new Float64Array(3 * DR_K); // the normalised channels, [ch DR_K + k]
const DR_R = new Float64Array(3 * DR_K); // windowed coefficients (coefficient-major RGB) of the subnormal path
const DR_F = new Float64Array(DR_K); // one channel's normalised 3-band target, then one channel's windowed target
const DR_G = new Float64Array(3);
const DR_A = new Float64Array(9); // the quadratic part, row-major 3 x 3
const DR_V = new Float64Array(9); // its eigenvectors (columns)
const DR_C0 = new Float64Array(3); // per channel: the constant, the eigenvalues (ascending), their gaps to the first
const DR_LAM = new Float64Array(9); // and (g . v_i)^2 / 4, at [3 ch + i]
const DR_GAP = new Float64Array(9);
const DR_SQ = new Float64Array(9);
const DR_D = new Float64Array(3);
const DR_AR = new Float64Array(3);
let deringFailed = false; // whether the last deringInPlace found no passing row

/** Channel ch of the flat n-band c, divided by 2^e (max |c| then in [1/2, 1), e as numpy.frexp's), into DR_T;
 * a zero channel as the constant 1 (its minimum, 0, passes as 1's does). Returns e (0 for a zero channel). */
function normalise(c, n, ch) {
  const o = ch * DR_K;
  let m = 0.0;
  for (let k = 0; k < n * n; k++) m = Math.max(m, Math.abs(c[3 * k + ch]));
  if (!(m > 0.0)) {
    for (let k = 0; k < n * n; k++) DR_T[o + k] = k === 0 ? 1.0 : 0.0;
    return 0;
  }
  let e = Math.floor(Math.log2(m)) + 1;
  if (m < Math.pow(2, e - 1)) e -= 1;
  if (m >= Math.pow(2, e)) e += 1;
  const h = Math.floor(e / 2), a = Math.pow(2, -h), b = Math.pow(2, h - e); // two exact steps: 2^-e may overflow
  for (let k = 0; k < n * n; k++) DR_T[o + k] = c[3 * k + ch] * a * b;
  return e;
}

/** Channel ch's 3-band target (its first min(n, 3)^2 normalised coefficients times A_l) as c0 + g . u + u^T A u
 * over the unit sphere (docs/conventions.md); returns c0, g into DR_G, A into DR_A. */
function deringForm(n, ch) {
  const [Y00, KL, KB, K0, K2] = DERING.basis, f = DR_F, g = DR_G, A = DR_A;
  for (let k = 0; k < 9; k++) f[k] = k < n * n ? DR_T[ch * DR_K + k] * DR_KERNEL[k === 0 ? 0 : k < 4 ? 1 : 2] : 0.0;
  g[0] = -KL * f[3];
  g[1] = -KL * f[1];
  g[2] = KL * f[2];
  A[0] = K2 * f[8] - K0 * f[6];
  A[4] = -K0 * f[6] - K2 * f[8];
  A[8] = 2.0 * K0 * f[6];
  A[1] = A[3] = 0.5 * KB * f[4];
  A[2] = A[6] = -0.5 * KB * f[7];
  A[5] = A[7] = -0.5 * KB * f[5];
  return Y00 * f[0];
}

/** Channel ch's spectrum: the eigenvalues of DR_A (cyclic Jacobi rotations) ascending, their gaps to the first and
 * (g . v_i)^2 / 4, into DR_LAM, DR_GAP, DR_SQ at 3 ch. */
function deringEigen(ch) {
  const A = DR_A, V = DR_V, g = DR_G, o = 3 * ch, lam = DR_LAM, a = DR_SQ;
  for (let k = 0; k < 9; k++) V[k] = k % 4 === 0 ? 1.0 : 0.0;
  for (let sweep = 0; sweep < 8; sweep++) {
    for (let pair = 0; pair < 3; pair++) {
      const p = pair === 2 ? 1 : 0, q = pair === 0 ? 1 : 2, apq = A[p * 3 + q];
      if (apq === 0.0) continue;
      const theta = (A[q * 3 + q] - A[p * 3 + p]) / (2.0 * apq);
      const t = (theta >= 0.0 ? 1.0 : -1.0) / (Math.abs(theta) + Math.sqrt(theta * theta + 1.0));
      const cs = 1.0 / Math.sqrt(t * t + 1.0), sn = t * cs;
      for (let k = 0; k < 3; k++) {
        const akp = A[k * 3 + p], akq = A[k * 3 + q], vkp = V[k * 3 + p], vkq = V[k * 3 + q];
        A[k * 3 + p] = cs * akp - sn * akq;
        A[k * 3 + q] = sn * akp + cs * akq;
        V[k * 3 + p] = cs * vkp - sn * vkq;
        V[k * 3 + q] = sn * vkp + cs * vkq;
      }
      for (let k = 0; k < 3; k++) {
        const apk = A[p * 3 + k], aqk = A[q * 3 + k];
        A[p * 3 + k] = cs * apk - sn * aqk;
        A[q * 3 + k] = sn * apk + cs * aqk;
      }
    }
  }
  for (let i = 0; i < 3; i++) {
    lam[o + i] = A[i * 4];
    const gam = V[i] * g[0] + V[3 + i] * g[1] + V[6 + i] * g[2];
    a[o + i] = 0.25 * gam * gam;
  }
  for (let i = 0; i < 2; i++) {
    for (let j = o; j < o + 2 - i; j++) {
      if (lam[j] > lam[j + 1]) {
        const tl = lam[j], ta = a[j];
        lam[j] = lam[j + 1];
        lam[j + 1] = tl;
        a[j] = a[j + 1];
        a[j + 1] = ta;
      }
    }
  }
  for (let i = 0; i < 3; i++) DR_GAP[o + i] = lam[o + i] - lam[o];
}

/** Channel ch's certified minimum less the rounding allowance with the window (1, s1, s2) (skysh.sh.minimum: the
 * dual after the proven start, one Newton step, the cluster bounds and the remaining steps). */
function deringDual(ch, s1, s2) {
  const [TINY, FLOOR, POLE, ALLOWANCE] = DERING.guards, d = DR_D, ar = DR_AR, o = 3 * ch;
  let x = FLOOR, cum = 0.0;
  for (let i = 0; i < 3; i++) {
    d[i] = DR_GAP[o + i] * s2;
    ar[i] = DR_SQ[o + i] * (s1 * s1);
    cum += ar[i];
    x = Math.max(x, Math.sqrt(cum) - d[i]);
  }
  let low = x;
  for (let it = 0; it <= DERING.steps; it++) {
    let s = 0.0, tt = 0.0;
    for (let i = 0; i < 3; i++) {
      const w = 1.0 / (d[i] + x), aw2 = ar[i] * w * w;
      s += aw2;
      tt += aw2 * w;
    }
    x = Math.max(x + (Math.sqrt(s) - 1.0) * s / (tt + TINY), low);
    if (it !== 0) continue;
    let big = 0.0;
    for (let k = 1; k < 3; k++) { // the cluster bounds
      big += ar[k - 1];
      let c0s = 0.0, t0s = 0.0;
      for (let i = k; i < 3; i++) {
        const far = Math.max(d[i] - d[k - 1], POLE), u = ar[i] / (far * far);
        c0s += u;
        t0s += u / far;
      }
      t0s += TINY;
      const near = Math.min(Math.sqrt(big / (2.0 * Math.max(1.0 - c0s, 0.0) + TINY)), Math.cbrt(big / (4.0 * t0s)));
      x = Math.max(x, Math.max((Math.sqrt(c0s) - 1.0) * c0s / t0s, near) - d[k - 1]);
    }
    low = x;
  }
  let sum = 0.0;
  for (let i = 0; i < 3; i++) sum += ar[i] / (d[i] + x);
  return DR_C0[ch] + DR_LAM[o] * s2 - x - sum - ALLOWANCE;
}

// The certificate (skysh.sh.minimum.certified_min, thr = 0): the target's values at DIRECTIONS Fibonacci directions
// (level 0), refuted by any negative one; else per channel, with K = sum_l l^2 |f_l| bandNorm[l] (Bernstein,
// bandNorm[l] = sqrt((2l+1)/(4 pi))) bounding the curvature along great circles, a direction's cell (the square
// [-COVER, COVER]^2 of its tangent plane under the exponential map) is kept while value - K r^2 / 2 - rounding < 0
// (r its half-diagonal) and split into SPLIT x SPLIT, for LEVELS levels: the minimum is >= 0 when no cell is left; a
// negative value, more than BUDGET cells, or a least value below the last level's slack K final + rounding
// (hopeless; final = (COVER / SPLIT^LEVELS)^2) stops it, not certified.
const CERT = DERING.certificate;
const CERT_M = CERT === null ? 0 : CERT.directions;
const DR_BEST = new Float64Array(3);
const DR_HINT = new Int32Array(3); // per channel, the direction of the last least level-0 value
let drAllow = 0.0; // the sampling allowance of the last certifiedTarget
let GRID = null; // built at first use: directions, tangent frames, the basis and the work buffers

/** The real SH of n bands at the unit vector (x, y, z) into out[o + i stride] (skysh.sh.basis's recurrence). */
function shBasis(x, y, z, n, out, o, stride) {
  const { cm, sm, q: Q, diag, next, ra, rb } = GRID;
  cm[0] = 1.0;
  sm[0] = 0.0;
  for (let m = 1; m < n; m++) {
    cm[m] = x * cm[m - 1] - y * sm[m - 1];
    sm[m] = x * sm[m - 1] + y * cm[m - 1];
  }
  let q2 = 0, q1 = MAX_BANDS, q = 2 * MAX_BANDS; // rolling rows Q[l - 2], Q[l - 1], Q[l] (indexed by m)
  for (let l = 0; l < n; l++) {
    for (let m = 0; m < l - 1; m++) Q[q + m] = Q[q1 + m] * z * ra[l * MAX_BANDS + m] - Q[q2 + m] * rb[l * MAX_BANDS + m];
    if (l >= 1) Q[q + l - 1] = z * next[l];
    Q[q + l] = diag[l];
    const centre = l * l + l;
    out[o + centre * stride] = Q[q];
    for (let m = 1; m <= l; m++) {
      out[o + (centre + m) * stride] = Q[q + m] * cm[m];
      out[o + (centre - m) * stride] = Q[q + m] * sm[m];
    }
    const t = q2;
    q2 = q1;
    q1 = q;
    q = t;
  }
}

/** The level-0 grid at first use: Fibonacci directions, their tangent frames (Duff et al. 2017), their basis. */
function grid() {
  if (GRID !== null) return GRID;
  const M = CERT_M, cells = Math.max(M, CERT.budget * CERT.split * CERT.split);
  GRID = {
    dirs: new Float64Array(3 * M), e1: new Float64Array(3 * M), e2: new Float64Array(3 * M),
    basis: new Float64Array(DR_K * M), bands: new Float64Array(3 * MAX_BANDS * M), // [j K + k]; [(3 j + ch) n + l]
    lo: new Float64Array(3 * M), hi: new Float64Array(3 * M), val: new Float64Array(3 * M), y: new Float64Array(DR_K),
    cm: new Float64Array(MAX_BANDS), sm: new Float64Array(MAX_BANDS), q: new Float64Array(3 * MAX_BANDS),
    diag: new Float64Array(CERT.diag), next: new Float64Array(CERT.next), ra: new Float64Array(CERT.a),
    rb: new Float64Array(CERT.b),
    root: [new Int32Array(cells), new Int32Array(cells)], cx: [new Float64Array(cells), new Float64Array(cells)],
    cy: [new Float64Array(cells), new Float64Array(cells)],
  };
  const { dirs, e1, e2 } = GRID;
  for (let j = 0; j < M; j++) {
    const i = j + 0.5, z = 1.0 - 2.0 * i / M, phi = i * Math.PI * CERT.golden;
    const s = Math.sqrt(Math.max(0.0, 1.0 - z * z)), x = s * Math.cos(phi), y = s * Math.sin(phi);
    const sign = z < 0.0 || Object.is(z, -0.0) ? -1.0 : 1.0, a = -1.0 / (sign + z), b = x * y * a;
    dirs.set([x, y, z], 3 * j);
    e1.set([1.0 + sign * x * x * a, sign * b, -sign * x], 3 * j);
    e2.set([b, sign + y * y * a, -y], 3 * j);
    shBasis(x, y, z, MAX_BANDS, GRID.basis, j * DR_K, 1);
  }
  return GRID;
}

/** Per direction j, channel and band l, the sum over band l's coefficients of DR_T times the level-0 basis, into
 * GRID.bands[(3 j + ch) n + l]. */
function levelBands(n) {
  const { basis, bands } = grid(), M = CERT_M, K = DR_K, T = DR_T;
  for (let j = 0; j < M; j++) {
    const y = j * K, o = 3 * j * n;
    for (let l = 0; l < n; l++) {
      let s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (let k = l * l; k < (l + 1) * (l + 1); k++) {
        const b = basis[y + k];
        s0 += T[k] * b;
        s1 += T[K + k] * b;
        s2 += T[2 * K + k] * b;
      }
      bands[o + l] = s0;
      bands[o + n + l] = s1;
      bands[o + 2 * n + l] = s2;
    }
  }
}

/** The level-0 value at direction j of channel ch with window row `row` (A_l times its factors p at row n). */
function levelValue(p, row, n, ch, j) {
  const o = (3 * j + ch) * n, b = GRID.bands;
  let v = 0.0;
  for (let l = 0; l < n; l++) v += p[row + l] * b[o + l];
  return v;
}

/** The level-0 values of window row `row` of channel ch into into[ch M + j]. */
function levelRow(n, row, ch, into) {
  const M = CERT_M, p = DR_TARGET[n - 1], b = GRID.bands, o = ch * M;
  for (let j = 0, q = ch * n; j < M; j++, q += 3 * n) {
    let v = 0.0;
    for (let l = 0; l < n; l++) v += p[row * n + l] * b[q + l];
    into[o + j] = v;
  }
}

/** The value at (x, y, z) of the K coefficients f (one channel's windowed target). */
function shValue(f, n, x, y, z) {
  const out = GRID.y;
  shBasis(x, y, z, n, out, 0, 1);
  let v = 0.0;
  for (let k = 0; k < n * n; k++) v += out[k] * f[k];
  return v;
}

/** Whether certified_min(f, 0) of one channel's windowed target f (DR_F) is >= 0, from its level-0 values vals
 * at o, its curvature bound k2 and rounding allowance allow. */
function certify(n, vals, o, k2, allow) {
  const g = grid(), M = CERT_M, S = CERT.split, C = CERT.cover;
  let best = Infinity, count = 0, cur = 0;
  for (let j = 0; j < M; j++) best = Math.min(best, vals[o + j]);
  const slack = 0.5 * k2 * (C * C) + allow, hopeless = k2 * CERT.final + allow;
  for (let j = 0; j < M; j++) {
    if (vals[o + j] - slack < Math.min(best, 0.0)) {
      g.root[0][count] = j;
      g.cx[0][count] = 0.0;
      g.cy[0][count++] = 0.0;
    }
  }
  let half = C;
  for (let level = 0; level < CERT.levels; level++) {
    if (count === 0) return true;
    if (count > CERT.budget || best < hopeless) return false; // frozen: the bound stays below 0
    const root = g.root[cur], cx = g.cx[cur], cy = g.cy[cur], nroot = g.root[1 - cur], ncx = g.cx[1 - cur];
    const ncy = g.cy[1 - cur], step = half;
    let kept = 0;
    half /= S;
    for (let c = 0; c < count; c++) {
      const d = 3 * root[c];
      for (let a = 0; a < S; a++) {
        for (let b = 0; b < S; b++) {
          const u = cx[c] + step * ((2.0 * a + 1.0) / S - 1.0), w = cy[c] + step * ((2.0 * b + 1.0) / S - 1.0);
          const r = Math.hypot(u, w), t = r / Math.PI, sc = t === 0.0 ? 1.0 : Math.sin(Math.PI * t) / (Math.PI * t);
          const cr = Math.cos(r);
          let px = cr * g.dirs[d] + sc * (u * g.e1[d] + w * g.e2[d]);
          let py = cr * g.dirs[d + 1] + sc * (u * g.e1[d + 1] + w * g.e2[d + 1]);
          let pz = cr * g.dirs[d + 2] + sc * (u * g.e1[d + 2] + w * g.e2[d + 2]);
          const norm = Math.sqrt(px * px + py * py + pz * pz);
          px /= norm;
          py /= norm;
          pz /= norm;
          const v = shValue(DR_F, n, px, py, pz);
          if (v < 0.0) return false; // a negative value: refuted
          best = Math.min(best, v);
          if (v - k2 * half * half - allow < 0.0) {
            nroot[kept] = root[c];
            ncx[kept] = u;
            ncy[kept++] = w;
          }
        }
      }
    }
    count = kept;
    cur = 1 - cur;
  }
  return count === 0;
}

/** Whether the certificate puts every channel of the window at fraction f between rows lo and hi (target factors
 * P_lo + f (P_hi - P_lo), level-0 values GRID.lo + f (GRID.hi - GRID.lo); a whole row lo when lo === hi, its
 * values from the band sums) at >= 0. Each channel's last least direction is tried first: a negative value there
 * refutes the window at once, as the full scan would. */
function certifiedPasses(n, lo, hi, f) {
  const g = GRID, M = CERT_M, p = DR_TARGET[n - 1], C = CERT.cover, best = DR_BEST, whole = lo === hi;
  for (let ch = 0; ch < 3; ch++) {
    const j = DR_HINT[ch], v = whole ? levelValue(p, lo * n, n, ch, j) : g.lo[ch * M + j] + f * (g.hi[ch * M + j] - g.lo[ch * M + j]);
    if (v < 0.0) return false;
  }
  for (let ch = 0; ch < 3; ch++) {
    best[ch] = Infinity;
    if (whole) levelRow(n, lo, ch, g.val);
    for (let j = 0, o = ch * M; j < M; j++) {
      const v = whole ? g.val[o + j] : g.lo[o + j] + f * (g.hi[o + j] - g.lo[o + j]);
      g.val[o + j] = v;
      if (v < best[ch]) {
        best[ch] = v;
        DR_HINT[ch] = j;
        if (v < 0.0) return false; // a sampled negative value in some channel
      }
    }
  }
  for (let ch = 0; ch < 3; ch++) {
    const k2 = certifiedTarget(n, lo, hi, f, ch), allow = drAllow;
    if (best[ch] - 0.5 * k2 * (C * C) - allow < 0.0 && !certify(n, g.val, ch * M, k2, allow)) return false;
  }
  return true;
}

/** Channel ch's windowed target at fraction f between rows lo and hi (DR_T times P_lo + f (P_hi - P_lo)) into DR_F;
 * returns its curvature bound K (skysh.sh.minimum.curvature), its sampling allowance into drAllow. */
function certifiedTarget(n, lo, hi, f, ch) {
  const p = DR_TARGET[n - 1];
  let k2 = 0.0, sum = 0.0;
  for (let l = 0; l < n; l++) {
    const w = p[lo * n + l] + f * (p[hi * n + l] - p[lo * n + l]);
    let norm = 0.0;
    for (let k = l * l; k < (l + 1) * (l + 1); k++) {
      DR_F[k] = DR_T[ch * DR_K + k] * w;
      norm += DR_F[k] * DR_F[k];
    }
    norm = Math.sqrt(norm) * CERT.bandNorm[l];
    k2 += norm * (l * l);
    sum += norm;
  }
  drAllow = CERT.rounding * sum;
  return k2;
}

/** The least passing fraction of the step from row - 1 to row, certified (skysh.post.dering._fraction and _bisect,
 * candidate for candidate): from the start, the least f at which every level-0 value (GRID.lo + f (GRID.hi -
 * GRID.lo)) reaches the last level's slack K(f) final + allowance(f) (each side linear in f; below it no certificate
 * passes), floored to a multiple of 1 / q; then candidates one multiple above it, stepping 1, 2, 4, .. multiples up
 * while they fail (down from a first pass) until the answer is bracketed, then bisection on multiples. */
function certifiedFraction(n, row, q) {
  const M = CERT_M, g = GRID, TINY = DERING.guards[0];
  let start = 0.0;
  for (let ch = 0; ch < 3; ch++) {
    const klo = certifiedTarget(n, row - 1, row, 0.0, ch), olo = klo * CERT.final + drAllow;
    const khi = certifiedTarget(n, row - 1, row, 1.0, ch), ohi = khi * CERT.final + drAllow;
    for (let j = ch * M; j < (ch + 1) * M; j++) {
      const glo = g.lo[j] - olo, ghi = g.hi[j] - ohi;
      if (glo < 0.0) start = Math.max(start, glo / Math.min(glo - ghi, -TINY));
    }
  }
  let lo = Math.floor(Math.min(start, 1.0) * q) / q, hi = 1.0, step = 1.0, go = true, down = false, fresh = true;
  let cand = Math.min(Math.max(Math.ceil((lo + 1.0 / q) * q), lo * q + 1.0), q) / q;
  while (hi - lo > 1.0 / q) {
    const ok = windowPasses(n, row - 1, row, cand);
    if (ok) hi = cand;
    else lo = cand;
    if (fresh) down = ok;
    go = go && (fresh || ok === down); // galloping on while the side stays the same
    fresh = false;
    const next = down ? hi - step / q : lo + step / q;
    go = go && next > lo && next < hi;
    if (go) step *= 2.0;
    cand = go ? next : Math.floor(0.5 * (lo + hi) * q) / q;
  }
  return hi;
}

/** Whether the window at fraction f between rows lo and hi of the n-band table passes in every channel. */
function windowPasses(n, lo, hi, f) {
  if (!DR_EXACT[n - 1]) return certifiedPasses(n, lo, hi, f);
  const rows = DR_TABLES[n - 1];
  const s1 = n < 2 ? 0.0 : rows[lo * n + 1] + f * (rows[hi * n + 1] - rows[lo * n + 1]);
  const s2 = n < 3 ? 0.0 : rows[lo * n + 2] + f * (rows[hi * n + 2] - rows[lo * n + 2]);
  for (let ch = 0; ch < 3; ch++) if (deringDual(ch, s1, s2) < 0.0) return false;
  return true;
}

/** What every window's decision reads from DR_T: the spectra (1..4 bands) or the level-0 band sums. */
function deringPrepare(n) {
  if (!DR_EXACT[n - 1]) {
    levelBands(n);
    return;
  }
  for (let ch = 0; ch < 3; ch++) {
    DR_C0[ch] = deringForm(n, ch);
    deringEigen(ch);
  }
}

/** The least passing whole row of DR_T's function, DR_ROWS if none. */
function leastRow(n) {
  for (let r = 0; r < DR_ROWS; r++) if (windowPasses(n, r, r, 0.0)) return r;
  return DR_ROWS;
}

/** A function with a subnormal channel: the least row whose windowed coefficients, as rounded, pass at row 0. */
function leastRowRounded(c, n) {
  const rows = DR_TABLES[n - 1];
  for (let r = 0; r < DR_ROWS; r++) {
    for (let k = 0; k < n * n; k++) {
      const s = rows[r * n + Math.floor(Math.sqrt(k))];
      for (let ch = 0; ch < 3; ch++) DR_R[3 * k + ch] = c[3 * k + ch] * s;
    }
    for (let ch = 0; ch < 3; ch++) normalise(DR_R, n, ch);
    deringPrepare(n);
    if (windowPasses(n, 0, 0, 0.0)) return r;
  }
  return DR_ROWS;
}

/** Window the n-band radiance c (flat, coefficient-major RGB) in place as the runtime's dering; returns the window's
 * position along the table (deringFailed: whether no row passes, the last then applied). */
function deringInPlace(c, n) {
  let tiny = false;
  for (let ch = 0; ch < 3; ch++) {
    const e = normalise(c, n, ch);
    tiny = tiny || (e !== 0 && e <= SUBNORMAL);
  }
  let row = 0, fraction = 1.0;
  if (tiny) {
    row = leastRowRounded(c, n);
  } else {
    deringPrepare(n);
    row = leastRow(n);
    if (row > 0 && row < DR_ROWS) { // the least passing multiple of 1 / LATTICE in (0, 1]: 0 fails, 1 passes
      const steps = DR_LATTICE[n - 1];
      if (!DR_EXACT[n - 1]) { // the passing row's values are GRID.val
        GRID.hi.set(GRID.val);
        for (let ch = 0; ch < 3; ch++) levelRow(n, row - 1, ch, GRID.lo);
        fraction = certifiedFraction(n, row, steps);
      } else { // exact: bisection, the passing fractions being one interval
        let lo = 0, hi = steps;
        while (hi - lo > 1) {
          const mid = (lo + hi) >>> 1;
          if (windowPasses(n, row - 1, row, mid / steps)) hi = mid;
          else lo = mid;
        }
        fraction = hi / steps;
      }
    }
  }
  deringFailed = row === DR_ROWS;
  const position = deringFailed ? DR_ROWS - 1 : row === 0 || tiny ? row : row - 1 + fraction;
  const rows = DR_TABLES[n - 1], i = Math.min(Math.floor(position), DR_ROWS - 1), f = position - i;
  const j = Math.min(i + 1, DR_ROWS - 1); // a whole position is its row exactly
  for (let l = 0; l < n; l++) {
    const s = rows[i * n + l] + f * (rows[j * n + l] - rows[i * n + l]);
    for (let k = l * l * 3; k < (l + 1) * (l + 1) * 3; k++) c[k] *= s;
  }
  return position;
}
