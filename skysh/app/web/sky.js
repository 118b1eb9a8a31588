// skysh viewer: the CPU side of the page, in double precision, no DOM (it also runs under node).
// The true Preetham sky (1999, appendix) and the Hosek-Wilkie sky (2012, eq. 9: its ES module's radiance), the real SH basis (skysh.sh.basis's recurrence), the error
// numbers, the number formats of the engine snippets and the read-out text. Every constant comes from the page's
// configuration, which skysh.app.viewer generates from skysh.model.preetham, skysh.sh.basis and skysh.engines.presets;
// the zenith luminance is the page's JavaScript runtime's own (skysh.export.js's module: the formula written once).
"use strict";

(function () {
  const TWO_PI = 2.0 * Math.PI;

  /** Perez A..E at turbidity t from (slope, intercept) rows. */
  function perezAt(table, t) {
    return table.map((row) => row[0] * t + row[1]);
  }

  /** Perez F = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma); exp term 0 at or below the horizon. */
  function perez(p, cosTheta, gamma, cosGamma) {
    const horizon = cosTheta > 0.0 ? Math.exp(p[1] / cosTheta) : 0.0;
    return (1.0 + p[0] * horizon) * (1.0 + p[2] * Math.exp(p[3] * gamma) + p[4] * cosGamma * cosGamma);
  }

  /** Angle between unit vectors d and s, accurate near 0: atan2(|d x s|, d . s). */
  function angle(dx, dy, dz, s) {
    const cx = dy * s[2] - dz * s[1], cy = dz * s[0] - dx * s[2], cz = dx * s[1] - dy * s[0];
    return Math.atan2(Math.sqrt(cx * cx + cy * cy + cz * cz), dx * s[0] + dy * s[1] + dz * s[2]);
  }

  /** [T^2, T, 1] M [ts^3, ts^2, ts, 1]^T: Preetham's zenith chromaticity. */
  function chromaticity(m, ts, t) {
    const tv = [t * t, t, 1.0], sv = [ts * ts * ts, ts * ts, ts, 1.0];
    let sum = 0.0;
    for (let i = 0; i < 3; i++) for (let j = 0; j < 4; j++) sum += tv[i] * m[i][j] * sv[j];
    return sum;
  }

  /**
   * The sky's CPU side for config (skysh.app.viewer.page_config) and runtime, the page's JavaScript runtime (the
   * module of skysh.export.js), whose zenithLuminance(ts, t) (cd/m^2, unchecked) the true sky takes; hosek (optional),
   * the Hosek-Wilkie ES module (skysh.export.hosek), whose configuration() and radiance() the Hosek-Wilkie sky takes.
   */
  function create(config, runtime, hosek = null) {
    const zenithLuminance = runtime.zenithLuminance;
    if (typeof zenithLuminance !== "function") {
      throw new TypeError("SkyshSky.create needs the runtime's zenithLuminance(sunZenith, turbidity) (skysh.app.viewer hands it over)");
    }
    const rgb = config.xyzToRgb;
    const rec = config.shRecurrence;
    const maxBands = config.maxBands;
    const lobe = config.lobe;

    /**
     * Everything the sky needs per (sun zenith, turbidity, azimuth): the shader's uniforms too. model "hosek-wilkie":
     * the Hosek-Wilkie sky at the grey ground albedo, its parameters (hosek: A..I, LM, efficacy, each [r, g, b]) from
     * the module's configuration(); else the Preetham sky.
     */
    function skyState(ts, t, phi, model = "preetham", albedo = 0.0) {
      phi %= TWO_PI;
      const st = Math.sin(ts);
      const sun = [st * Math.cos(phi), st * Math.sin(phi), Math.cos(ts)];
      if (model === "hosek-wilkie") {
        return { model, sunZenith: ts, turbidity: t, sunAzimuth: phi, albedo, sun, hosek: hosek.configuration(ts, t, albedo) };
      }
      const zenith = [chromaticity(config.zenithX, ts, t), chromaticity(config.zenithY, ts, t), zenithLuminance(ts, t)];
      const perezXyY = [perezAt(config.perez.x, t), perezAt(config.perez.y, t), perezAt(config.perez.Y, t)];
      const gammaZ = angle(0.0, 0.0, 1.0, sun); // the zenith on the path of every view, as skysh.model.preetham.xyY
      const cosGammaZ = Math.cos(gammaZ);
      const fz = perezXyY.map((p) => perez(p, 1.0, gammaZ, cosGammaZ));
      const scale = zenith.map((z, q) => z / fz[q]); // the shader's value = scale F
      return { model, sunZenith: ts, turbidity: t, sunAzimuth: phi, sun, zenith, perez: perezXyY, fz, scale };
    }

    /** Linear RGB radiance (cd/m^2) of the true sky towards unit (dx, dy, dz) into out[k..k+2]; 0 below the horizon. */
    function radiance(state, dx, dy, dz, out, k) {
      if (state.model === "hosek-wilkie") { // the module's own radiance (0 below the horizon)
        const v = hosek.radiance([dx, dy, dz], state.sunZenith, state.turbidity, state.sunAzimuth, state.albedo);
        out[k] = v[0];
        out[k + 1] = v[1];
        out[k + 2] = v[2];
        return;
      }
      if (dz < 0.0) {
        out[k] = out[k + 1] = out[k + 2] = 0.0;
        return;
      }
      const gamma = angle(dx, dy, dz, state.sun);
      const cg = Math.cos(gamma);
      const zen = state.zenith, p = state.perez, fz = state.fz;
      // the zenith value times F / F(zenith), as skysh.model.preetham.xyY
      const x = zen[0] * (perez(p[0], dz, gamma, cg) / fz[0]);
      const y = zen[1] * (perez(p[1], dz, gamma, cg) / fz[1]);
      const Y = zen[2] * (perez(p[2], dz, gamma, cg) / fz[2]);
      const X = (x * Y) / y, Z = ((1.0 - x - y) * Y) / y;
      out[k] = rgb[0][0] * X + rgb[0][1] * Y + rgb[0][2] * Z;
      out[k + 1] = rgb[1][0] * X + rgb[1][1] * Y + rgb[1][2] * Z;
      out[k + 2] = rgb[2][0] * X + rgb[2][1] * Y + rgb[2][2] * Z;
    }

    const cm = new Float64Array(maxBands), sm = new Float64Array(maxBands);
    const rows = [new Float64Array(maxBands), new Float64Array(maxBands), new Float64Array(maxBands)];

    /** Real orthonormal SH with the Condon-Shortley phase of n bands at unit (x, y, z) into out[k..]: skysh.sh.basis.basis's recurrence. */
    function basis(x, y, z, n, out, k) {
      cm[0] = 1.0;
      sm[0] = 0.0;
      for (let m = 1; m < n; m++) {
        cm[m] = x * cm[m - 1] - y * sm[m - 1];
        sm[m] = x * sm[m - 1] + y * cm[m - 1];
      }
      let q2 = rows[0], q1 = rows[1], q = rows[2];
      for (let l = 0; l < n; l++) {
        if (l >= 2) {
          const a = rec.a[l], b = rec.b[l];
          for (let m = 0; m < l - 1; m++) q[m] = q1[m] * z * a[m] - q2[m] * b[m];
        }
        if (l >= 1) q[l - 1] = z * (Math.sqrt(2 * l + 1) * rec.diag[l - 1]);
        q[l] = rec.diag[l];
        const centre = k + l * l + l;
        out[centre] = q[0];
        for (let m = 1; m <= l; m++) {
          out[centre + m] = q[m] * cm[m];
          out[centre - m] = q[m] * sm[m];
        }
        const t = q2;
        q2 = q1;
        q1 = q;
        q = t;
      }
    }

    // The error rule: Gauss-Legendre in cos(theta) times equally spaced azimuths, both hemispheres.
    const rule = config.errorRule;
    const nMu = rule.mu.length, nPhi = rule.azimuths;
    const count = nMu * nPhi;
    const ruleDirs = new Float64Array(2 * count * 3); // upper hemisphere, then its mirror below
    const ruleWeights = new Float64Array(count);
    for (let i = 0; i < nMu; i++) {
      const mu = rule.mu[i], s = Math.sqrt(Math.max(0.0, 1.0 - mu * mu));
      for (let j = 0; j < nPhi; j++) {
        const phi = (TWO_PI * (j + 0.5)) / nPhi, k = i * nPhi + j;
        ruleWeights[k] = (rule.weights[i] * TWO_PI) / nPhi;
        for (const [half, sign] of [[0, 1.0], [1, -1.0]]) {
          const o = 3 * (half * count + k);
          ruleDirs[o] = s * Math.cos(phi);
          ruleDirs[o + 1] = s * Math.sin(phi);
          ruleDirs[o + 2] = sign * mu;
        }
      }
    }
    const nb = maxBands * maxBands;
    const ruleBasis = new Float64Array(2 * count * nb);
    for (let k = 0; k < 2 * count; k++) basis(ruleDirs[3 * k], ruleDirs[3 * k + 1], ruleDirs[3 * k + 2], maxBands, ruleBasis, k * nb);
    const truth = new Float64Array(3 * count);

    /**
     * The page's numbers for one sky and its reconstruction c (n bands, coefficient-major RGB):
     * relative RMS error over the upper hemisphere, ringing (RMS below the horizon over the sky's
     * RMS above it), and the log-average of the sky's RGB mean (the auto exposure's reference).
     */
    function metrics(state, c, n) {
      let diff = 0.0, norm = 0.0, below = 0.0, logSum = 0.0, weightSum = 0.0;
      for (let k = 0; k < count; k++) radiance(state, ruleDirs[3 * k], ruleDirs[3 * k + 1], ruleDirs[3 * k + 2], truth, 3 * k);
      for (let half = 0; half < 2; half++) {
        for (let k = 0; k < count; k++) {
          const base = (half * count + k) * nb;
          let r = 0.0, g = 0.0, b = 0.0;
          for (let i = 0; i < n * n; i++) {
            const y = ruleBasis[base + i];
            r += y * c[3 * i];
            g += y * c[3 * i + 1];
            b += y * c[3 * i + 2];
          }
          const w = ruleWeights[k];
          if (half === 0) {
            const tr = truth[3 * k], tg = truth[3 * k + 1], tb = truth[3 * k + 2];
            diff += w * ((r - tr) ** 2 + (g - tg) ** 2 + (b - tb) ** 2);
            norm += w * (tr * tr + tg * tg + tb * tb);
            logSum += w * Math.log(Math.max((tr + tg + tb) / 3.0, 1e-6));
            weightSum += w;
          } else {
            below += w * (r * r + g * g + b * b);
          }
        }
      }
      return { error: Math.sqrt(diff / norm), ringing: Math.sqrt(below / norm), logAverage: Math.exp(logSum / weightSum) };
    }

    return { skyState, radiance, basis, metrics, lobe, maxBands, ruleSize: count };
  }

  /** Python's repr of a double: the shortest round-trip digits, exponent form below 1e-4 or from 1e16. */
  function pyRepr(x) {
    if (Object.is(x, -0)) return "-0.0";
    if (x === 0) return "0.0";
    if (!Number.isFinite(x)) return Number.isNaN(x) ? "nan" : x > 0 ? "inf" : "-inf";
    const [mantissa, exponentText] = x.toExponential().split("e"); // shortest round-trip digits
    const exponent = Number(exponentText);
    const sign = mantissa.startsWith("-") ? "-" : "";
    const digits = mantissa.replace("-", "").replace(".", "");
    if (exponent < -4 || exponent >= 16) {
      const body = digits.length > 1 ? `${digits[0]}.${digits.slice(1)}` : digits;
      const e = Math.abs(exponent);
      return `${sign}${body}e${exponent < 0 ? "-" : "+"}${e < 10 ? "0" : ""}${e}`;
    }
    if (exponent < 0) return `${sign}0.${"0".repeat(-exponent - 1)}${digits}`;
    const whole = digits.slice(0, exponent + 1).padEnd(exponent + 1, "0");
    const fraction = digits.slice(exponent + 1);
    return `${sign}${whole}.${fraction || "0"}`;
  }

  /** The number formats of skysh.engines.presets.snippet (skysh.app.viewer._NUMBER_FORMATS). */
  const NUMBER_FORMATS = { js: pyRepr, f32: (x) => `${pyRepr(x)}f` };

  /** Fill a snippet template: {{k:fmt}} is values[k] written in format fmt. */
  function fillSnippet(template, values) {
    return template.replace(/\{\{(\d+):(\w+)\}\}/g, (_, k, fmt) => NUMBER_FORMATS[fmt](values[Number(k)]));
  }

  // ------------------------------------------------------------------ the read-out
  /**
   * Numbers below this fraction of the DC term print as 0 (and -0 as 0): rounding noise of the rotation to the
   * sun's azimuth (terms that are zero for the sky come out near 1e-17 of DC). skysh.engines.presets.snippet's rule too.
   */
  const NOISE_FLOOR = 1e-12;

  /** The DC term of coefficient-major RGB coefficients c: the largest |coefficient of row 0| over the channels. */
  function dcTerm(c) {
    return Math.max(Math.abs(c[0]), Math.abs(c[1]), Math.abs(c[2]));
  }

  /** values as the read-out prints them: each |v| below NOISE_FLOOR * dc, and -0, as 0. */
  function printable(values, dc) {
    const floor = NOISE_FLOOR * dc;
    return Array.from(values, (v) => (v === 0 || Math.abs(v) < floor ? 0 : v));
  }

  const DEG = Math.PI / 180.0;
  const NUMBER_LIST = /\[\s*(-?[0-9.eE+-]+(?:,\s*-?[0-9.eE+-]+)*)\s*\]/g;

  function nest(values, shape) {
    const rows = [];
    const width = values.length / shape[0];
    for (let i = 0; i < shape[0]; i++) rows.push(Array.prototype.slice.call(values, i * width, (i + 1) * width));
    return rows;
  }

  /**
   * The runtime's options of the controls s (unticked table: the old pipeline, as irradiance_table=False); for the
   * Hosek-Wilkie sky (s.model) the albedo instead: it has no table.
   */
  function runtimeOptions(s, extra) {
    if (s.model === "hosek-wilkie") return { bands: s.bands, gibbs: s.gibbs, dering: s.dering, albedo: s.albedo, ...extra };
    return { bands: s.bands, gibbs: s.gibbs, dering: s.dering, ...(s.irradianceTable ? {} : { irradianceTable: false }), ...extra };
  }

  /** Whether the runtime takes the certified irradiance table for these controls (its rule, by intent). */
  function usesTable(s, diffuse) {
    return s.model !== "hosek-wilkie" && s.irradianceTable && diffuse && s.bands === 3 && !s.gibbs && s.dering;
  }

  /**
   * The Hosek-Wilkie ES module (skysh.export.hosek) behind the Preetham runtime's call coefficients(sunZenith,
   * turbidity, sunAzimuth, {bands, ...options}): one createSky(bands) per band count, built on first use. No engine
   * map (the module has none: ENGINES is empty).
   */
  function hosekRuntime(module) {
    const skies = new Map();
    function coefficients(ts, t, phi, options = {}) {
      const { bands = module.MAX_BANDS, ...rest } = options;
      if (!skies.has(bands)) skies.set(bands, module.createSky(bands));
      return skies.get(bands).coefficients(ts, t, phi, rest);
    }
    return { ...module, coefficients, ENGINES: Object.freeze([]) };
  }

  /** The numbers of the read-out and their DC term: of the coefficients, or of the radiance an engine converts. */
  function readoutValues(runtime, s) {
    const frame = [s.sunZenith, s.turbidity, s.sunAzimuth];
    if (s.engine === null) {
      const values = runtime.coefficients(...frame, runtimeOptions(s, { irradiance: s.irradiance }));
      return { values, dc: dcTerm(values) };
    }
    const values = runtime.coefficients(...frame, runtimeOptions(s, { engine: s.engine }));
    const radiance = runtime.coefficients(...frame, runtimeOptions(s, { irradianceTable: usesTable(s, true) }));
    return { values, dc: dcTerm(radiance) };
  }

  /**
   * The read-out text for the controls s (viewer.js's controls()): the coefficients as `skysh coeffs --format json`
   * writes them, or the engine snippet; numbers below NOISE_FLOOR of DC as 0. runtime: the JavaScript runtime of
   * skysh.export.c_like; config: skysh.app.viewer.page_config.
   */
  function readout(runtime, config, s) {
    let values, dc;
    try {
      ({ values, dc } = readoutValues(runtime, s));
    } catch (error) {
      return `// ${error.message}`;
    }
    values = printable(values, dc);
    if (s.readoutFormat === "snippet") {
      if (s.engine === null) return "// Choose an engine preset for a paste-ready snippet (the JSON holds skysh's own coefficients).";
      return fillSnippet(config.snippets[s.engine][String(s.bands)], values);
    }
    const hosek = s.model === "hosek-wilkie";
    const info = {
      skysh_version: runtime.SKYSH_VERSION,
      model: hosek ? "hosek-wilkie" : "preetham",
      ...(hosek ? { albedo: s.albedo } : {}),
      quantity: s.irradiance ? "irradiance" : "radiance",
      bands: s.bands,
      sun_zenith_deg: s.sunZenith / DEG,
      sun_azimuth_deg: s.sunAzimuth / DEG,
      sun_zenith_rad: s.sunZenith,
      sun_azimuth_rad: s.sunAzimuth,
      turbidity: s.turbidity,
      gibbs: s.gibbs,
      dering: s.dering,
      ...(hosek ? {} : { irradiance_table: usesTable(s, s.irradiance || s.engine !== null) }),
      colourspace: config.colourspace,
    };
    let payload;
    if (s.engine !== null) {
      const layout = runtime.engineLayout(s.engine, s.bands);
      payload = { values: nest(values, layout.shape), engine: s.engine, shape: layout.shape, labels: layout.labels, ...info };
    } else {
      const lm = [];
      for (let l = 0; l < s.bands; l++) for (let m = -l; m <= l; m++) lm.push([l, m]);
      payload = {
        coefficients: nest(values, [s.bands * s.bands]), lm, ...info, up: "z",
        units: s.irradiance ? "cd/m^2*sr" : "cd/m^2",
        convention: "real orthonormal SH with the Condon-Shortley phase, index l(l+1)+m; Z up, azimuth from +X towards +Y",
      };
    }
    return JSON.stringify(payload, null, 1).replace(NUMBER_LIST, (_, list) => `[${list.split(/\s+/).join(" ")}]`);
  }

  globalThis.SkyshSky = {
    create, pyRepr, fillSnippet, NUMBER_FORMATS, NOISE_FLOOR, dcTerm, printable, runtimeOptions, usesTable, hosekRuntime,
    readout,
  };
})();
