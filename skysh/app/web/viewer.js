// skysh viewer: the page. Controls -> coefficients (skysh's JavaScript runtimes of the Preetham and the
// Hosek-Wilkie sky, both inlined in index.html) -> one WebGL2 canvas drawn panel by panel, the error numbers and the read-out.
// A control change schedules one animation frame that does all of it (nothing is deferred).
// globalThis.skyshViewer also serves the browser tests (state, nextFrame, readPanel, ...).
"use strict";

(function () {
  const DEG = Math.PI / 180.0;
  const viewer = { frame: 0, startupMs: null, updateMs: null };
  globalThis.skyshViewer = viewer;
  let resolveReady;
  viewer.ready = new Promise((resolve) => { resolveReady = resolve; });

  const $ = (id) => document.getElementById(id);
  let config, sky, runtime, gl, programs, canvas, panels;
  const runtimes = {}; // model -> its runtime (the Hosek-Wilkie module behind SkyshSky.hosekRuntime); runtime: the Preetham one
  const hosekModel = () => $("model").value === "hosek-wilkie";
  const runtimeFor = (model) => runtimes[model];
  let current = null; // everything the last frame computed
  let pending = false;
  const frameWaiters = [];

  // ------------------------------------------------------------------ controls
  const RANGES = ["sun-zenith", "sun-azimuth", "turbidity", "albedo", "bands", "ev"];
  const CHECKS = ["gibbs", "dering", "irradiance-table", "mark-negative", "irradiance"];
  const SELECTS = ["model", "engine", "readout-format"];

  function controls() {
    const value = (id) => Number($(id).value);
    const model = $("model").value, rt = runtimeFor(model);
    const [zmin, zmax] = rt.SUN_ZENITH_DOMAIN, [tmin, tmax] = rt.TURBIDITY_DOMAIN;
    const bands = Math.round(value("bands"));
    const engine = $("engine").value || null;
    return {
      model,
      albedo: model === "hosek-wilkie" ? value("albedo") : 0.0,
      sunZenithDeg: value("sun-zenith"),
      sunAzimuthDeg: value("sun-azimuth"),
      // degrees -> radians, kept inside the runtime's domain (90 deg may round a hair above pi/2)
      sunZenith: Math.min(Math.max(value("sun-zenith") * DEG, zmin), zmax),
      sunAzimuth: value("sun-azimuth") * DEG,
      turbidity: Math.min(Math.max(value("turbidity"), tmin), tmax),
      bands,
      gibbs: $("gibbs").checked,
      dering: $("dering").checked,
      irradianceTable: $("irradiance-table").checked,
      markNegative: $("mark-negative").checked,
      ev: value("ev"),
      engine,
      irradiance: engine === null && $("irradiance").checked,
      readoutFormat: $("readout-format").value,
    };
  }

  /** Defaults by intent, as the Python runtime: diffuse (irradiance, engines) -> no Gibbs, deringing on. */
  function applyIntent() {
    const diffuse = $("engine").value !== "" || $("irradiance").checked;
    $("gibbs").checked = !diffuse;
    $("dering").checked = diffuse;
  }

  /**
   * The model's ranges: the turbidity slider spans its runtime's domain (the value clamped into it), the bands its
   * runtime's; the Hosek-Wilkie sky has no engine map, so the engine preset goes back to none (and its intent).
   */
  function applyModel() {
    const rt = runtimeFor($("model").value);
    const [tmin, tmax] = rt.TURBIDITY_DOMAIN, t = Number($("turbidity").value);
    $("turbidity").min = String(tmin);
    $("turbidity").max = String(tmax);
    $("turbidity").value = String(Math.min(Math.max(t, tmin), tmax));
    $("bands").max = String(rt.MAX_BANDS);
    if (hosekModel() && $("engine").value !== "") {
      $("engine").value = "";
      applyIntent();
    }
  }

  /** Controls that depend on others (deringing needs a runtime that has it; the model), and the values shown. */
  function syncControls() {
    const bands = Math.round(Number($("bands").value));
    const hosek = hosekModel();
    const available = (hosek ? viewer.hosekDeringBands : viewer.deringBands).includes(bands);
    $("dering").disabled = !available;
    if (!available) $("dering").checked = false; // what is shown is what is applied
    $("dering-note").textContent = available ? "" : `(not in this runtime for ${bands} bands)`;
    $("irradiance").disabled = $("engine").value !== "";
    if ($("irradiance").disabled) $("irradiance").checked = false;
    $("irradiance-table").disabled = hosek || !viewer.hasIrradianceTable;
    if (!viewer.hasIrradianceTable) $("irradiance-table").checked = false;
    $("irradiance-table-note").textContent = hosek ? "(Preetham only: the Hosek-Wilkie runtime has none)"
      : viewer.hasIrradianceTable ? "" : "(not in this runtime)";
    $("engine").disabled = hosek;
    $("engine-note").textContent = hosek ? "(Preetham only: the Hosek-Wilkie runtime has no engine map)" : "";
    $("albedo-row").hidden = !hosek;
    $("model-note").hidden = !hosek;
    const [tmin, tmax] = runtimeFor($("model").value).TURBIDITY_DOMAIN;
    $("turbidity-domain").textContent = `[${tmin}, ${tmax}]`;
    for (const el of document.querySelectorAll(".model-name")) el.textContent = hosek ? "Hosek-Wilkie" : "Preetham";
    const number = (id) => Number($(id).value);
    $("albedo-out").value = number("albedo").toFixed(2);
    $("sun-zenith-out").value = number("sun-zenith").toFixed(1);
    $("sun-azimuth-out").value = number("sun-azimuth").toFixed(1);
    $("turbidity-out").value = number("turbidity").toFixed(2);
    $("bands-out").value = `${bands} (${bands * bands} coefficients)`;
    $("ev-out").value = (number("ev") >= 0 ? "+" : "") + number("ev").toFixed(1);
  }

  function onInput(event) {
    if (event.target.id === "engine" || event.target.id === "irradiance") applyIntent();
    if (event.target.id === "model") applyModel();
    syncControls();
    schedule();
  }

  function bindControls() {
    const engine = $("engine");
    for (const name of runtime.ENGINES) engine.add(new Option(`${name} (at most ${config.engineMaxBands[name]} bands)`, name));
    for (const id of [...RANGES, ...CHECKS, ...SELECTS]) $(id).addEventListener("input", onInput);
    $("copy").addEventListener("click", copyReadout);
    syncControls();
  }

  // ------------------------------------------------------------------ read-out
  // The text is SkyshSky.readout's (sky.js, no DOM: the tests run it under node too).
  const optionsOf = (s, extra) => SkyshSky.runtimeOptions(s, extra);

  async function copyReadout() {
    const text = $("readout").value;
    const status = $("copy-status");
    try {
      await navigator.clipboard.writeText(text);
      status.textContent = "copied";
    } catch (error) {
      $("readout").select();
      const copied = typeof document.execCommand === "function" && document.execCommand("copy");
      status.textContent = copied ? "copied" : "the browser refused the clipboard: the text is selected, copy it by hand";
    }
  }

  // ------------------------------------------------------------------ WebGL2
  function compile(type, source) {
    const shader = gl.createShader(type);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(`shader: ${gl.getShaderInfoLog(shader)}`);
    return shader;
  }

  const UNIFORMS = ["rect", "sh", "irr", "ground", "sun", "perez", "scale", "xyz_to_rgb", "hosek", "hw", "exposure",
    "mark_negative", "camera", "target"];
  const ARRAYS = ["sh", "irr", "perez", "hw"];
  const HW_ORDER = ["A", "B", "C", "D", "E", "F", "G", "H", "I"]; // u_hw's order (shaders.js), then L_M x efficacy

  function link(view) {
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, SkyshShaders.VERTEX));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, SkyshShaders.fragment(config, view)));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`program ${view}: ${gl.getProgramInfoLog(program)}`);
    const uniforms = {};
    for (const name of UNIFORMS) uniforms[name] = gl.getUniformLocation(program, `u_${name}${ARRAYS.includes(name) ? "[0]" : ""}`);
    return { program, uniforms };
  }

  function initGl() {
    canvas = $("gl");
    gl = canvas.getContext("webgl2", { antialias: false, alpha: true, premultipliedAlpha: true });
    if (!gl) throw new Error("WebGL2 is not available in this browser: the views need it (the read-out works without)");
    programs = Object.fromEntries(SkyshShaders.VIEWS.map((view) => [view, link(view)]));
    gl.bindVertexArray(gl.createVertexArray());
    panels = [...document.querySelectorAll(".view")].map((view) => ({
      name: view.parentElement.dataset.panel, view, program: programs[view.dataset.mode],
    }));
    new ResizeObserver(schedule).observe($("views"));
    canvas.addEventListener("webglcontextlost", (event) => { event.preventDefault(); $("footer").textContent = "WebGL context lost: reload the page."; });
  }

  function panelRect(panel, box, scale) {
    const r = panel.view.getBoundingClientRect();
    const x = Math.round((r.left - box.left + 1) * scale), top = Math.round((r.top - box.top + 1) * scale);
    const w = Math.round((r.width - 2) * scale), h = Math.round((r.height - 2) * scale); // inside the 1 px border
    return { x, y: canvas.height - top - h, w, h };
  }

  let UP = null; // the SH basis at the zenith (the ground's normal)

  /** Upload the frame's uniforms: the coefficients (radiance; irradiance as the runtime gives it), the sky, the exposure. */
  function setUniforms(state, coeffs, irr, exposure) {
    const n = state.bands, size = config.maxBands * config.maxBands * 3;
    const radiance = new Float32Array(size), irradiance = new Float32Array(size);
    const ground = [0.0, 0.0, 0.0];
    sky.basis(0.0, 0.0, 1.0, n, UP, 0);
    for (let k = 0; k < 3 * n * n; k++) {
      radiance[k] = coeffs[k];
      irradiance[k] = irr[k];
      ground[k % 3] += (UP[Math.floor(k / 3)] * irr[k]) / Math.PI;
    }
    const m = config.xyzToRgb;
    const xyzToRgb = [m[0][0], m[1][0], m[2][0], m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2]];
    const hosek = state.sky.model === "hosek-wilkie";
    const hw = new Float32Array(30);
    if (hosek) {
      const p = state.sky.hosek;
      HW_ORDER.forEach((name, q) => hw.set(p[name], 3 * q));
      hw.set(p.LM.map((v) => v * p.efficacy), 27); // in double, then rounded to float once
    }
    for (const { program, uniforms } of Object.values(programs)) { // uniforms are per program
      gl.useProgram(program);
      gl.uniform3fv(uniforms.sh, radiance);
      gl.uniform3fv(uniforms.irr, irradiance);
      gl.uniform3fv(uniforms.ground, ground);
      gl.uniform3fv(uniforms.sun, state.sky.sun);
      gl.uniform1i(uniforms.hosek, hosek ? 1 : 0);
      gl.uniform3fv(uniforms.hw, hw);
      if (!hosek) {
        gl.uniform1fv(uniforms.perez, state.sky.perez.flat());
        gl.uniform3fv(uniforms.scale, state.sky.scale);
      }
      gl.uniformMatrix3fv(uniforms.xyz_to_rgb, false, xyzToRgb);
      gl.uniform1f(uniforms.exposure, exposure);
      gl.uniform1i(uniforms.mark_negative, state.markNegative ? 1 : 0);
      gl.uniform3fv(uniforms.camera, [-4.6, -3.0, 1.9]);
      gl.uniform3fv(uniforms.target, [0.0, 0.0, 0.8]);
    }
  }

  /** Draw the panels (all, or the one named `only`); their rectangles in canvas pixels. */
  function draw(state, coeffs, irr, exposure, only = null) {
    const scale = Math.min(window.devicePixelRatio || 1, 2);
    const box = canvas.getBoundingClientRect();
    const width = Math.round(box.width * scale), height = Math.round(box.height * scale);
    if (canvas.width !== width || canvas.height !== height) { canvas.width = width; canvas.height = height; }
    gl.disable(gl.SCISSOR_TEST);
    gl.viewport(0, 0, width, height);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT);
    setUniforms(state, coeffs, irr, exposure);
    gl.enable(gl.SCISSOR_TEST);
    const rects = {};
    for (const panel of panels) {
      const r = panelRect(panel, box, scale);
      rects[panel.name] = r;
      if (r.w <= 0 || r.h <= 0 || (only !== null && panel.name !== only)) continue;
      gl.viewport(r.x, r.y, r.w, r.h);
      gl.scissor(r.x, r.y, r.w, r.h);
      gl.useProgram(panel.program.program);
      gl.uniform4f(panel.program.uniforms.rect, r.x, r.y, r.w, r.h);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }
    return rects;
  }

  // ------------------------------------------------------------------ overlays
  function marker(view, className) {
    let el = view.querySelector(`.${className}`);
    if (!el) {
      el = document.createElement("div");
      el.className = className;
      view.appendChild(el);
    }
    return el;
  }

  function axisLabel(view, key, text, css) {
    const el = marker(view, `axis-${key}`);
    el.classList.add("axis");
    el.textContent = text;
    Object.assign(el.style, css);
  }

  function overlays(state) {
    const phi = state.sky.sunAzimuth, ts = state.sunZenith;
    for (const panel of panels) {
      const view = panel.view;
      if (view.classList.contains("fisheye")) {
        const r = ts / (Math.PI / 2) * 50; // percent of the half width
        const sun = marker(view, "marker");
        sun.style.left = `${50 + r * Math.sin(phi)}%`;
        sun.style.top = `${50 - r * Math.cos(phi)}%`;
        axisLabel(view, "x", "+X", { left: "50%", top: "2px" });
        axisLabel(view, "y", "+Y", { right: "4px", top: "50%" });
      } else if (view.classList.contains("latlong")) {
        const wrapped = phi - 2 * Math.PI * Math.round(phi / (2 * Math.PI)); // [-pi, pi], as math.remainder
        const sun = marker(view, "marker");
        sun.style.left = `${(wrapped + Math.PI) / (2 * Math.PI) * 100}%`;
        sun.style.top = `${ts / Math.PI * 100}%`;
        marker(view, "horizon");
        axisLabel(view, "w", "-180\u00b0", { left: "3px", bottom: "2px" });
        axisLabel(view, "c", "0\u00b0", { left: "50%", bottom: "2px" });
        axisLabel(view, "e", "180\u00b0", { right: "3px", bottom: "2px" });
      }
    }
  }

  // ------------------------------------------------------------------ the frame
  function percent(x) {
    return x >= 0.1 ? `${(100 * x).toFixed(1)} %` : `${(100 * x).toPrecision(3)} %`;
  }

  function render(only = null) {
    const start = performance.now();
    const s = controls();
    s.sky = sky.skyState(s.sunZenith, s.turbidity, s.sunAzimuth, s.model, s.albedo);
    const rt = runtimeFor(s.model);
    const coeffs = rt.coefficients(s.sunZenith, s.turbidity, s.sunAzimuth, optionsOf(s, {}));
    // the scene's irradiance as the runtime gives it (the certified table by intent), not A_l times the radiance
    const irr = rt.coefficients(s.sunZenith, s.turbidity, s.sunAzimuth, optionsOf(s, { irradiance: true }));
    const numbers = sky.metrics(s.sky, coeffs, s.bands);
    const exposure = (config.keyValue / numbers.logAverage) * 2 ** s.ev;
    const rects = gl ? draw(s, coeffs, irr, exposure, only) : {};
    overlays(s);
    $("error-value").textContent = percent(numbers.error);
    $("ringing-value").textContent = percent(numbers.ringing);
    $("exposure-value").textContent = `${exposure.toPrecision(4)} per cd/m\u00b2`;
    const text = SkyshSky.readout(rt, config, s);
    if ($("readout").value !== text) $("readout").value = text;
    current = { ...s, coefficients: Array.from(coeffs), irradianceCoefficients: Array.from(irr), exposure, ...numbers, rects };
    viewer.frame += 1;
    viewer.updateMs = performance.now() - start;
    $("update-ms").textContent = `${viewer.updateMs.toFixed(1)} ms (CPU, last change)`;
  }

  function frame() {
    pending = false;
    render();
    if (viewer.startupMs === null) {
      viewer.startupMs = performance.now(); // since the navigation started
      $("footer").textContent = `skysh ${runtime.SKYSH_VERSION}: first frame ${viewer.startupMs.toFixed(0)} ms after navigation.`;
      resolveReady();
    }
    for (const resolve of frameWaiters.splice(0)) resolve(viewer.frame);
  }

  function schedule() {
    if (!pending) {
      pending = true;
      requestAnimationFrame(frame);
    }
  }

  function fatal(error) {
    const box = document.createElement("p");
    box.className = "fatal";
    box.textContent = `The viewer could not start: ${error.message}`;
    $("views").prepend(box);
  }

  // ------------------------------------------------------------------ start and test hooks
  /** The band counts whose deringing rt has. */
  function deringBands(rt) {
    const bands = [];
    for (let n = 1; n <= rt.MAX_BANDS; n++) {
      try {
        rt.coefficients(0.5, 3.0, 0.0, { bands: n, dering: true });
        bands.push(n);
      } catch (error) {
        if (!(error instanceof RangeError)) throw error; // this runtime has no deringing for n bands
      }
    }
    return bands;
  }

  /** Each inlined module script hands its runtime over (model: "preetham" or "hosek-wilkie"); the page starts with both. */
  viewer.register = function register(model, rt) {
    runtimes[model] = model === "hosek-wilkie" ? SkyshSky.hosekRuntime(rt) : rt;
    if (model === "hosek-wilkie") viewer.hosekModule = rt;
    if (runtimes.preetham && runtimes["hosek-wilkie"]) start();
  };

  function start() {
    runtime = runtimes.preetham;
    config = JSON.parse($("skysh-config").textContent);
    sky = SkyshSky.create(config, runtime, viewer.hosekModule);
    UP = new Float64Array(config.maxBands * config.maxBands);
    viewer.deringBands = deringBands(runtime);
    viewer.hosekDeringBands = deringBands(runtimes["hosek-wilkie"]);
    try { // the certified irradiance table: a 3-band runtime of a format-4 file
      runtime.coefficients(0.5, 3.0, 0.0, { bands: 3, irradiance: true, irradianceTable: true });
      viewer.hasIrradianceTable = true;
    } catch (error) {
      if (!(error instanceof RangeError)) throw error;
      viewer.hasIrradianceTable = false;
    }
    $("bands").max = String(runtime.MAX_BANDS);
    $("rule-size").textContent = String(sky.ruleSize);
    bindControls();
    try {
      initGl();
    } catch (error) {
      gl = null;
      fatal(error);
      console.error(error);
    }
    schedule();
  }

  /** What the last frame computed (controls, coefficients, error numbers, exposure, panel rectangles). */
  viewer.state = () => (current === null ? null : JSON.parse(JSON.stringify(current)));

  /** Promise of the next frame's number. */
  viewer.nextFrame = () => new Promise((resolve) => { frameWaiters.push(resolve); schedule(); });

  /** Draw a panel now and read its pixels: {width, height, rgba (base64, rows top to bottom)}. */
  viewer.readPanel = (name) => {
    render(name); // this panel only; the next frame draws them all again
    schedule();
    const r = current.rects[name];
    const pixels = new Uint8Array(r.w * r.h * 4);
    gl.readPixels(r.x, r.y, r.w, r.h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    const flipped = new Uint8Array(pixels.length);
    const row = r.w * 4;
    for (let y = 0; y < r.h; y++) flipped.set(pixels.subarray((r.h - 1 - y) * row, (r.h - y) * row), y * row);
    let binary = "";
    for (let i = 0; i < flipped.length; i += 0x8000) binary += String.fromCharCode(...flipped.subarray(i, i + 0x8000));
    return { width: r.w, height: r.h, rgba: btoa(binary) };
  };

  /** The CPU sky and basis at flat unit vectors [x0, y0, z0, x1, ...] (for the tests). */
  viewer.trueRadiance = (sunZenith, turbidity, sunAzimuth, dirs, model = "preetham", albedo = 0.0) => {
    const state = sky.skyState(sunZenith, turbidity, sunAzimuth, model, albedo);
    const out = new Float64Array(dirs.length);
    for (let k = 0; k < dirs.length; k += 3) sky.radiance(state, dirs[k], dirs[k + 1], dirs[k + 2], out, k);
    return Array.from(out);
  };
  viewer.basis = (dirs, n) => {
    const out = new Float64Array((dirs.length / 3) * n * n);
    for (let k = 0; k < dirs.length / 3; k++) sky.basis(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2], n, out, k * n * n);
    return Array.from(out);
  };
  viewer.pyRepr = (values) => values.map(SkyshSky.pyRepr);
})();
