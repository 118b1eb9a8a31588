// A hand-written JavaScript floor for the module's per-frame arithmetic (issue 26), and the timing of module vs floor.
//
// Run through benchmarks/bench_js_floor.py (it writes the module, its data object and the cases, then runs this):
//   PYTHONPATH=. python benchmarks/bench_js_floor.py [--calls 4000] [--rounds 15] [--only CASE ...]
// or by hand: node benchmarks/js_floor.mjs MODULE.mjs DATA.json CASES.json [calls = 4000] [rounds = 15]
//
// makeFloor(data, options) returns floor(sunZenith, turbidity, sunAzimuth, out): the least code that does the
// module's arithmetic for ONE fixed set of options, reading the same numbers (the module's data object, DATA, as
// skysh.export.js writes it): the Chebyshev terms by recurrence, the products T_i(x) T_j(y), the rows' dot products
// over a table of the same size (each row's terms contiguous, three sums a row: a term-major layout, the rows of
// one term contiguous and the sums in an array, measured 1.7x slower at 3 bands), the luminance scale, the Z rotation
// by the angle-addition recurrence from one cos and one sin, and for the lights the sun's fitted RGB (its own
// Chebyshev terms), the ground's c_10 and the sun's trigonometric polynomial (cos and sin of k ts by the same
// recurrence). No validation, no options: everything that depends on the options only (the per-band factors, Gibbs
// times A_l) is folded in when the floor is made. No deringing: a case with deringing times the module's whole call
// against the floor's sky without it (the deringing is its own cost).
//
// The timing: per case, a fresh instance of the module and of the floor (each gathers its own type feedback); the
// module's call and the floor's take turns in rounds (module, floor, module, ...), each round `calls` frames (the
// same random frames for both), after a warm-up round of each; the median ns per call of each over `rounds` rounds.
// The clock is the process's CPU time (process.cpuUsage, microseconds; a round lasts milliseconds), not wall time:
// on a shared machine whose load exceeds its cores the wall time of a round doubles or quadruples whenever the
// process waits for a core (measured: 850 ns per call vs 3,700 at load 5 on 2 cores, from one run to the next). A
// checksum of every result is kept so that no call is optimised away. The floor's agreement with the module: max
// |floor - module| over |DC| of the same channel, worst channel, over the first 500 frames. Prints one JSON line per
// case.
import { readFileSync } from "node:fs";
import { pathToFileURL } from "node:url";

/** The floor of one set of options: { bands, gibbs, irradiance, table, sun, albedo } (albedo a number, 0: none). */
export function makeFloor(data, { bands: n, gibbs, irradiance, table, sun, albedo }) {
  const [DX, DY] = data.degrees, TERMS = (DX + 1) * (DY + 1), [XS, XO] = data.x, [YS, YO] = data.y;
  const sky = data.table;
  const rows = (n * (n + 1)) / 2, ground = albedo > 0.0;
  // The rows the floor reads ([row][term][channel], as the module's table): the sky's first rows, or the irradiance
  // table's 6 rows and then the sky's c_10 row when the ground needs it (as the module's IRRADIANCE).
  const extra = table && ground ? 1 : 0, R = rows + extra, T = new Float64Array(TERMS * R * 3);
  T.set((table ? data.irradiance : sky).slice(0, TERMS * rows * 3));
  if (extra) T.set(sky.slice(TERMS * 3, TERMS * 6), TERMS * rows * 3);
  const lobe = data.lobe, g0 = (n * (n - 1)) / 2;
  const band = new Float64Array(n), zonal = new Float64Array(n); // the per-band factors, folded once
  for (let l = 0; l < n; l++) {
    band[l] = irradiance ? lobe[l] : 1.0;
    zonal[l] = gibbs ? data.gibbs[g0 + l] : 1.0;
  }
  const PY = data.perezY, ZY = data.zenithLuminance;
  const TX = new Float64Array(DX + 1), TY = new Float64Array(DY + 1), W = new Float64Array(TERMS);
  const ACC = new Float64Array(R * 3), COS = new Float64Array(n), SIN = new Float64Array(n);
  // The lights.
  const L = data.lights, K = L.constants, [SDX, SDY] = L.sunDegrees, ST = L.sunTable, M = L.rgbFromXyz;
  const SX = new Float64Array(SDX + 1), SY = new Float64Array(SDY + 1), MB = data.maxBands;
  const GROUND = new Float64Array(n), TRIGC = new Float64Array(rows * n), TRIGS = new Float64Array(rows * n);
  for (let l = 0; l < n; l++) GROUND[l] = L.ground[l] * zonal[l] * albedo * K.inv_pi;
  for (let l = 0, r = 0; l < n; l++) { // the sun's polynomial of one row, windowed for n bands
    for (let k = 0; k <= l; k++, r++) {
      const w = L.windows[g0 + l], src = (l * (l + 1) / 2 + k) * 2 * MB;
      for (let q = 0; q < n; q++) {
        TRIGC[r * n + q] = L.trig[src + q] * w;
        TRIGS[r * n + q] = L.trig[src + MB + q] * w;
      }
    }
  }
  const KC = new Float64Array(n), KS = new Float64Array(n), RGB = new Float64Array(3);

  return function floor(ts, t, phi, out) {
    let x = ts * XS - XO, y = Math.log(t) * YS - YO;
    x = x < -1.0 ? -1.0 : x > 1.0 ? 1.0 : x;
    y = y < -1.0 ? -1.0 : y > 1.0 ? 1.0 : y;
    TX[0] = 1.0;
    TX[1] = x;
    for (let i = 2; i <= DX; i++) TX[i] = 2.0 * x * TX[i - 1] - TX[i - 2];
    TY[0] = 1.0;
    TY[1] = y;
    for (let j = 2; j <= DY; j++) TY[j] = 2.0 * y * TY[j - 1] - TY[j - 2];
    for (let i = 0, q = 0; i <= DX; i++) for (let j = 0; j <= DY; j++, q++) W[q] = TX[i] * TY[j];
    for (let k = 0, b = 0; k < 3 * R; k += 3) {
      let s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (let q = 0; q < TERMS; q++, b += 3) {
        const w = W[q];
        s0 += w * T[b];
        s1 += w * T[b + 1];
        s2 += w * T[b + 2];
      }
      ACC[k] = s0;
      ACC[k + 1] = s1;
      ACC[k + 2] = s2;
    }
    const ct = Math.cos(ts), st = Math.sin(ts);
    const chi = (4.0 / 9.0 - t / 120.0) * (Math.PI - 2.0 * ts);
    const yz = 1000.0 * ((ZY[0] * t - ZY[1]) * Math.tan(chi) - ZY[2] * t + ZY[3]);
    const f = (1.0 + (PY[0] * t + PY[1]) * Math.exp(PY[2] * t + PY[3]))
      * (1.0 + (PY[4] * t + PY[5]) * Math.exp((PY[6] * t + PY[7]) * ts) + (PY[8] * t + PY[9]) * ct * ct);
    const scale = yz / f;
    const c1 = Math.cos(phi), s1 = Math.sin(phi);
    COS[0] = 1.0;
    SIN[0] = 0.0;
    for (let m = 1; m < n; m++) {
      COS[m] = COS[m - 1] * c1 - SIN[m - 1] * s1;
      SIN[m] = SIN[m - 1] * c1 + COS[m - 1] * s1;
    }
    for (let l = 0, r = 0; l < n; l++) {
      const centre = l * (l + 1) * 3, z = scale * zonal[l];
      for (let c = 0; c < 3; c++) out[centre + c] = ACC[r * 3 + c] * z;
      r++;
      for (let k = 1; k <= l; k++, r++) {
        const cp = COS[k] * scale, sp = SIN[k] * scale;
        for (let c = 0; c < 3; c++) {
          out[centre + 3 * k + c] = ACC[r * 3 + c] * cp;
          out[centre - 3 * k + c] = ACC[r * 3 + c] * sp;
        }
      }
    }
    if (sun || ground) {
      RGB[0] = RGB[1] = RGB[2] = 0.0;
      if (sun) {
        const am = 1.0 / (ct + K.am_a * Math.pow(K.am_b - ts * K.deg, K.am_neg_c));
        let u = (am - K.m0) * K.sx_scale - 1.0, v = (t - K.sun_tmin) * K.sy_scale - 1.0;
        u = u < -1.0 ? -1.0 : u > 1.0 ? 1.0 : u;
        v = v < -1.0 ? -1.0 : v > 1.0 ? 1.0 : v;
        SX[0] = 1.0;
        SX[1] = u;
        for (let i = 2; i <= SDX; i++) SX[i] = 2.0 * u * SX[i - 1] - SX[i - 2];
        SY[0] = 1.0;
        SY[1] = v;
        for (let j = 2; j <= SDY; j++) SY[j] = 2.0 * v * SY[j - 1] - SY[j - 2];
        let l0 = 0.0, l1 = 0.0, l2 = 0.0;
        for (let i = 0, b = 0; i <= SDX; i++) {
          for (let j = 0; j <= SDY; j++, b += 3) {
            const w = SX[i] * SY[j];
            l0 += w * ST[b];
            l1 += w * ST[b + 1];
            l2 += w * ST[b + 2];
          }
        }
        const e0 = Math.exp(l0), e1 = Math.exp(l1), e2 = Math.exp(l2);
        for (let c = 0; c < 3; c++) RGB[c] = M[3 * c] * e0 + M[3 * c + 1] * e1 + M[3 * c + 2] * e2;
      }
      if (ground) {
        const c10 = extra ? rows * 3 : 3;
        for (let c = 0; c < 3; c++) {
          const lg = K.hf * scale * ACC[c10 + c] + ct * RGB[c];
          for (let l = 0; l < n; l++) out[l * (l + 1) * 3 + c] += GROUND[l] * lg;
        }
      }
      if (sun) {
        for (let c = 0; c < 3; c++) if (!(RGB[c] > K.clamp)) RGB[c] = K.clamp;
        KC[0] = 1.0;
        KS[0] = 0.0;
        for (let k = 1; k < n; k++) {
          KC[k] = KC[k - 1] * ct - KS[k - 1] * st;
          KS[k] = KS[k - 1] * ct + KC[k - 1] * st;
        }
        for (let l = 0, r = 0; l < n; l++) {
          for (let k = 0; k <= l; k++, r++) {
            let s = 0.0;
            for (let q = 0; q < n; q++) s += TRIGC[r * n + q] * KC[q] + TRIGS[r * n + q] * KS[q];
            const i3 = (l * (l + 1) + k) * 3, j3 = (l * (l + 1) - k) * 3, yp = s * COS[k], ym = s * SIN[k];
            for (let c = 0; c < 3; c++) out[i3 + c] += yp * RGB[c];
            if (k > 0) for (let c = 0; c < 3; c++) out[j3 + c] += ym * RGB[c];
          }
        }
      }
    }
    if (irradiance) {
      for (let l = 0; l < n; l++) for (let k = l * l * 3; k < (l + 1) * (l + 1) * 3; k++) out[k] *= band[l];
    }
    return out;
  };
}

/** Random frames (sun zenith in the domain, turbidity, azimuth), a fixed seed. */
function frames(count, [zmin, zmax], [tmin, tmax]) {
  let seed = 20260126;
  const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
  const f = new Float64Array(3 * count);
  for (let i = 0; i < count; i++) {
    f[3 * i] = zmin + (zmax - zmin) * random();
    f[3 * i + 1] = tmin + (tmax - tmin) * random();
    f[3 * i + 2] = 2.0 * Math.PI * (random() - 0.5);
  }
  return f;
}

function median(values) {
  const s = [...values].sort((a, b) => a - b), h = s.length >> 1;
  return s.length % 2 ? s[h] : 0.5 * (s[h - 1] + s[h]);
}

/** One round: CPU ns per call of fn over the frames (the process's user + system time, see above), and a checksum
 * of every result. */
function round(fn, input) {
  const count = input.length / 3;
  let check = 0.0;
  const start = process.cpuUsage();
  for (let i = 0; i < count; i++) {
    const c = fn(input[3 * i], input[3 * i + 1], input[3 * i + 2]);
    for (let k = 0; k < c.length; k++) check += c[k];
  }
  const used = process.cpuUsage(start);
  return [((used.user + used.system) * 1e3) / count, check];
}

/** The worst |a - b| over |DC| of the same channel, over the frames. */
function agreement(a, b, input) {
  let worst = 0.0;
  for (let i = 0; i < input.length; i += 3) {
    const u = Array.from(a(input[i], input[i + 1], input[i + 2])), v = b(input[i], input[i + 1], input[i + 2]);
    for (let k = 0; k < u.length; k++) worst = Math.max(worst, Math.abs(u[k] - v[k]) / Math.abs(u[k % 3]));
  }
  return worst;
}

async function main() {
  const [modulePath, dataPath, casesPath, calls = "4000", rounds = "15"] = process.argv.slice(2);
  if (!casesPath) throw new Error("usage: node js_floor.mjs MODULE.mjs DATA.json CASES.json [calls] [rounds]");
  const data = JSON.parse(readFileSync(dataPath, "utf8"));
  const cases = JSON.parse(readFileSync(casesPath, "utf8"));
  const input = frames(Number(calls), data.sunZenithDomain, data.turbidityDomain);
  for (const { name, options, floor: settings } of cases) {
    // A fresh instance of the module and of this file per case (a query makes a new module): each case's code
    // gathers its own type feedback, as in an application that calls with one set of options.
    const m = await import(`${pathToFileURL(modulePath).href}?${encodeURIComponent(name)}`);
    const { makeFloor: make } = await import(`${import.meta.url}?${encodeURIComponent(name)}`);
    const length = options.bands * options.bands * 3;
    const out = new Float64Array(length), floorOut = new Float64Array(length), given = { ...options, out };
    const moduleOut = (ts, t, phi) => m.coefficients(ts, t, phi, given);
    const moduleNew = (ts, t, phi) => m.coefficients(ts, t, phi, options);
    const f = make(data, settings), floorFn = (ts, t, phi) => f(ts, t, phi, floorOut);
    const diff = agreement(moduleNew, floorFn, input.subarray(0, 3 * Math.min(500, Number(calls))));
    const timed = { module: [], floor: [], alloc: [] };
    const fns = { module: moduleOut, floor: floorFn, alloc: moduleNew };
    for (const key in fns) round(fns[key], input); // warm-up
    let checksum = 0.0;
    for (let r = 0; r < Number(rounds); r++) {
      for (const key in fns) {
        const [ns, check] = round(fns[key], input);
        timed[key].push(ns);
        checksum += check;
      }
    }
    const mod = median(timed.module), flo = median(timed.floor);
    process.stdout.write(JSON.stringify({
      bench: name, module_ns_per_call: Math.round(mod), floor_ns_per_call: Math.round(flo),
      ratio: Math.round((mod / flo) * 100) / 100, module_new_array_ns_per_call: Math.round(median(timed.alloc)),
      floor_max_diff_over_dc: diff, checksum_finite: Number.isFinite(checksum),
    }) + "\n");
  }
}

if (process.argv[1] && import.meta.url === pathToFileURL(process.argv[1]).href) await main();
