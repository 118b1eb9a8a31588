// skysh viewer: the WebGL2 shaders, as strings. One full-viewport triangle per panel and one
// program per view. The SH basis is written out from the page's configuration (skysh.sh.basis's
// recurrence constants); the true sky takes skysh.model.preetham's tables as uniforms (through sky.js), or the
// Hosek-Wilkie parameters of its ES module's configuration() per frame, with skysh.model.hosek's horizon offset inlined.
"use strict";

(function () {
  const VERTEX = `#version 300 es
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
`;

  function floats(values) {
    return values.map((v) => {
      const text = Number(v).toPrecision(9);
      return /[.e]/.test(text) ? text : `${text}.0`;
    }).join(", ");
  }

  /**
   * Straight-line GLSL of the real SH basis (skysh.sh.basis's recurrence, constants inlined) summed
   * against a uniform array: no loops or dynamic indexing, which software rasterisers run slowly.
   * Unused coefficients are uploaded as zeros, so the sum always runs over every band.
   */
  function basisSum(config, name) {
    const n = config.maxBands, rec = config.shRecurrence;
    const lines = ["  float c0 = 1.0, s0 = 0.0;"];
    for (let m = 1; m < n; m++) {
      lines.push(`  float c${m} = d.x * c${m - 1} - d.y * s${m - 1}, s${m} = d.x * s${m - 1} + d.y * c${m - 1};`);
    }
    const terms = [];
    for (let l = 0; l < n; l++) {
      for (let m = 0; m <= l; m++) {
        let value;
        if (m === l) value = floats([rec.diag[l]]);
        else if (m === l - 1) value = `d.z * ${floats([Math.sqrt(2 * l + 1) * rec.diag[l - 1]])}`;
        else value = `${floats([rec.a[l][m]])} * d.z * q${l - 1}_${m} - ${floats([rec.b[l][m]])} * q${l - 2}_${m}`;
        lines.push(`  float q${l}_${m} = ${value};`);
        const c = l * l + l;
        terms.push(m === 0 ? `q${l}_0 * ${name}[${c}]` : `q${l}_${m} * (c${m} * ${name}[${c + m}] + s${m} * ${name}[${c - m}])`);
      }
    }
    return `${lines.join("\n")}\n  return ${terms.join("\n    + ")};`;
  }

  const LATLONG = `  // skysh.app.render's layout: azimuth -pi (left) to pi (right), zenith angle 0 (top) to pi (bottom)
  vec2 uv = (gl_FragCoord.xy - u_rect.xy) / u_rect.zw;
  float phi = -PI + 2.0 * PI * uv.x, theta = PI * (1.0 - uv.y);
  return vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));`;
  const FISHEYE = `  // Looking up: +X at the top, +Y to the right; the angle from the zenith grows linearly to the rim.
  vec2 p = 2.0 * (gl_FragCoord.xy - u_rect.xy - 0.5 * u_rect.zw) / min(u_rect.z, u_rect.w);
  float r = length(p);
  outside = r > 1.0;
  float theta = 0.5 * PI * min(r, 1.0);
  vec2 h = r > 0.0 ? p / r : vec2(0.0);
  return vec3(sin(theta) * h.y, sin(theta) * h.x, cos(theta));`;
  const VIEW_DIRECTIONS = { fisheyeSky: FISHEYE, fisheyeSh: FISHEYE, latlongSky: LATLONG, latlongSh: LATLONG };
  const VIEW_COLOURS = {
    fisheyeSky: "toneMap(trueSky(d))",
    fisheyeSh: "shown(shRadiance(d))",
    latlongSky: "toneMap(trueSky(d))",
    latlongSh: "shown(shRadiance(d))",
    scene: "scene(2.0 * (gl_FragCoord.xy - u_rect.xy - 0.5 * u_rect.zw) / min(u_rect.z, u_rect.w))",
  };

  /**
   * The fragment shader of one view (one of VIEWS), for skysh.sh.basis's recurrence constants:
   * one program per view, so no pixel pays for another view's branches.
   */
  function fragment(config, view) {
    if (!(view in VIEW_COLOURS)) throw new RangeError(`view must be one of ${Object.keys(VIEW_COLOURS).join(", ")}`);
    const n = config.maxBands;
    return `#version 300 es
precision highp float;
precision highp int;

const int N = ${n};
const float PI = 3.14159265358979;

uniform vec4 u_rect;        // the panel: x, y (from the bottom), width, height in pixels
uniform vec3 u_sh[N * N];   // radiance coefficients, linear RGB, cd/m^2 (zero beyond the bands shown)
uniform vec3 u_irr[N * N];  // irradiance coefficients E: A_l times the radiance's
uniform vec3 u_ground;      // E / pi of the ground (normal +Z), from the CPU
uniform vec3 u_sun;         // unit vector towards the sun, Z up
uniform float u_perez[15];  // Perez A..E of x, y and Y at the turbidity
uniform vec3 u_scale;       // zenith value / F(zenith) of x, y and Y
uniform mat3 u_xyz_to_rgb;
uniform bool u_hosek;       // the Hosek-Wilkie sky instead of the Preetham sky
uniform vec3 u_hw[10];      // its parameters A, B, C, D, E, F, G, H, I (eq. 9), then L_M x efficacy (cd/m^2), per channel
uniform float u_exposure;
uniform bool u_mark_negative;
uniform vec3 u_camera;
uniform vec3 u_target;
out vec4 fragColor;

float perezF(int q, float ct, float gamma, float cg) {
  int k = 5 * q;
  float horizon = ct > 0.0 ? exp(u_perez[k + 1] / ct) : 0.0;
  return (1.0 + u_perez[k] * horizon) * (1.0 + u_perez[k + 2] * exp(u_perez[k + 3] * gamma) + u_perez[k + 4] * cg * cg);
}

const float HW_HORIZON_OFFSET = ${floats([config.hosekHorizonOffset])}; // skysh.model.hosek.HORIZON_OFFSET

// The Hosek-Wilkie sky (2012, eq. 9) in linear sRGB, cd/m^2, as skysh.model.hosek.radiance; zero below the horizon.
vec3 hosekSky(vec3 d) {
  if (d.z < 0.0) return vec3(0.0);
  float gamma = atan(length(cross(d, u_sun)), dot(d, u_sun));
  float cg = cos(gamma);
  vec3 H = u_hw[7];
  vec3 den = 1.0 + H * (H - 2.0 * cg);
  vec3 chi = (1.0 + cg * cg) / (den * sqrt(den));
  vec3 f = (1.0 + u_hw[0] * exp(u_hw[1] / (d.z + HW_HORIZON_OFFSET)))
    * (u_hw[2] + u_hw[3] * exp(u_hw[4] * gamma) + u_hw[5] * cg * cg + u_hw[6] * chi + u_hw[8] * sqrt(d.z));
  return f * u_hw[9];
}

// The true sky in linear RGB, cd/m^2 (the Preetham sky unless u_hosek); zero below the horizon.
vec3 trueSky(vec3 d) {
  if (u_hosek) return hosekSky(d);
  if (d.z < 0.0) return vec3(0.0);
  float gamma = atan(length(cross(d, u_sun)), dot(d, u_sun));
  float cg = cos(gamma);
  float x = u_scale.x * perezF(0, d.z, gamma, cg);
  float y = u_scale.y * perezF(1, d.z, gamma, cg);
  float Y = u_scale.z * perezF(2, d.z, gamma, cg);
  return u_xyz_to_rgb * vec3(x * Y / y, Y, (1.0 - x - y) * Y / y);
}

// The SH reconstruction at unit d: radiance (u_sh) and irradiance E (u_irr), skysh.sh.basis.basis's order.
vec3 shRadiance(vec3 d) {
${basisSum(config, "u_sh")}
}
vec3 shIrradiance(vec3 d) {
${basisSum(config, "u_irr")}
}

// skysh.app.render.tone_map: exposure, Reinhard on the RGB mean, the sRGB transfer function.
vec3 srgb(vec3 v) {
  return mix(12.92 * v, 1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, v));
}
vec3 toneMap(vec3 rgb) {
  vec3 v = max(rgb * u_exposure, 0.0);
  return srgb(v / (1.0 + (v.r + v.g + v.b) / 3.0));
}
// Negative radiance (SH ringing) in magenta when asked, else as skysh.app.render (black).
vec3 shown(vec3 rgb) {
  float mean = (rgb.r + rgb.g + rgb.b) / 3.0;
  if (u_mark_negative && mean < 0.0) {
    float v = -mean * u_exposure;
    return srgb(vec3(v / (1.0 + v))) * vec3(1.0, 0.0, 1.0);
  }
  return toneMap(rgb);
}

vec3 scene(vec2 p) {
  vec3 f = normalize(u_target - u_camera);
  vec3 r = normalize(cross(f, vec3(0.0, 0.0, 1.0)));
  vec3 u = cross(r, f);
  vec3 d = normalize(f + 0.45 * (p.x * r + p.y * u));
  vec3 centre = vec3(0.0, 0.0, 1.0); // a unit sphere resting on the ground z = 0
  vec3 oc = u_camera - centre;
  float bq = dot(oc, d), disc = bq * bq - dot(oc, oc) + 1.0;
  if (disc > 0.0 && -bq - sqrt(disc) > 0.0) {
    vec3 n = normalize(oc + (-bq - sqrt(disc)) * d);
    return toneMap(0.8 * shIrradiance(n) / PI); // white-ish Lambertian: albedo E / pi
  }
  if (d.z < 0.0) {
    vec3 g = u_camera - (u_camera.z / d.z) * d;
    vec3 toSphere = centre - g;
    float dist = length(toSphere);
    float formFactor = toSphere.z / (dist * dist * dist); // the sphere's share of the ground's sky (R = 1)
    float checker = mod(floor(g.x) + floor(g.y), 2.0);
    float albedo = mix(0.3 + 0.08 * checker, 0.34, clamp(length(g.xy) / 30.0, 0.0, 1.0));
    return toneMap(albedo * (1.0 - formFactor) * u_ground);
  }
  return toneMap(trueSky(d));
}

// The view of this program (${view}).
vec3 direction(out bool outside) {
  outside = false;
${VIEW_DIRECTIONS[view] ?? "  return vec3(0.0);"}
}

void main() {
  bool outside;
  vec3 d = direction(outside);
  if (outside) discard;
  fragColor = vec4(${VIEW_COLOURS[view]}, 1.0);
}
`;
  }

  globalThis.SkyshShaders = { VIEWS: Object.freeze(Object.keys(VIEW_COLOURS)), VERTEX, fragment };
})();
