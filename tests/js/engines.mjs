// Runs three.js and Babylon.js (the versions pinned in package.json) on SH coefficient sets and
// prints what each engine computes, for tests/engines/test_engines.py. One process for all cases:
// JSON in on stdin, JSON out on stdout. Numbers travel as JSON, which both Python and
// JavaScript write as the shortest text that reads back as the same double.
//
// stdin:  {"threejs": {"dirs": [[x, y, z], ...], "sets": [[27 numbers], ...]},
//          "babylon": {"dirs": [...], "sets": [[27 numbers], ...]},
//          "babylonCubemap": {"size": S, "frame": [[3 x 3]], "sets": [[27 numbers], ...]}}
//         (dirs in the engine's own frame; sets flat, coefficient-major RGB, as convert() returns them;
//         babylonCubemap sets are skysh radiance SH, Z up, rendered into Babylon cube faces through
//         `frame`: a Babylon direction d shows the skysh radiance at frame^T d)
// stdout: {"threejs": {"getAt": R, "getIrradianceAt": R, "probeShader": R},
//          "babylon": {"harmonicsShader": R, "polynomialShader": R, "serializedShader": R},
//          "babylonCubemap": {"harmonics": H}}
//         R[set][dir] = [r, g, b]; H[set] = the 9 x 3 harmonics Babylon's cube-map projector keeps.
//
// Shader functions are not retyped here: the GLSL text shipped in each package is turned into a
// JavaScript function of one colour channel (types dropped, ".rgb" swizzles removed), so the
// arithmetic evaluated is the engine's own.

import { readFileSync } from 'node:fs';

import { LightProbe, SphericalHarmonics3, Vector3 } from 'three';
import { WebGLLights } from 'three/src/renderers/webgl/WebGLLights.js';
import lightsParsBegin from 'three/src/renderers/shaders/ShaderChunk/lights_pars_begin.glsl.js';

import { SphericalHarmonics, SphericalPolynomial } from '@babylonjs/core/Maths/sphericalPolynomial.js';
import { CubeMapToSphericalPolynomialTools }
  from '@babylonjs/core/Misc/HighDynamicRange/cubemapToSphericalPolynomial.js';
import { BindIBLParameters } from '@babylonjs/core/Materials/materialHelper.functions.js';
import { harmonicsFunctions } from '@babylonjs/core/Shaders/ShadersInclude/harmonicsFunctions.js';

const HARMONIC_NAMES = ['l00', 'l1_1', 'l10', 'l11', 'l2_2', 'l2_1', 'l20', 'l21', 'l22'];
const HARMONIC_UNIFORMS = HARMONIC_NAMES.map((n) => `vSpherical${n[0].toUpperCase()}${n.slice(1)}`); // vSphericalL00..

// GLSL body -> JavaScript body of one channel: declarations become `let`, swizzles of vec3 go.
function glslToJs(body) {
  return body.replace(/\b(?:vec3|float)\s+/g, 'let ').replace(/\.rgb\b/g, '');
}

function extract(source, pattern, what) {
  const match = source.match(pattern);
  if (!match) throw new Error(`could not find ${what} in the shipped shader text`);
  return match[1];
}

// three.js: shGetIrradianceAt( normal, shCoefficients[ 9 ] ) from lights_pars_begin.glsl.js
const threeIrradianceBody = extract(
  lightsParsBegin,
  /vec3 shGetIrradianceAt\(\s*in vec3 normal,\s*in vec3 shCoefficients\[\s*9\s*\]\s*\)\s*\{([\s\S]*?)\n\}/,
  'shGetIrradianceAt',
);
const threeShIrradianceAt = new Function('normal', 'shCoefficients', glslToJs(threeIrradianceBody));

// Babylon: both branches of computeEnvironmentIrradiance in harmonicsFunctions.fx
const [babylonHarmonicsText, babylonPolynomialText] = harmonicsFunctions.shader.split('#else');
const bodyPattern = /vec3 computeEnvironmentIrradiance\(vec3 normal\)\s*\{([\s\S]*?)\}\s*(?:#|$)/;
const babylonHarmonicsShader = new Function(
  'normal', ...HARMONIC_UNIFORMS,
  glslToJs(extract(babylonHarmonicsText, bodyPattern, 'the SPHERICAL_HARMONICS branch')),
);
const POLY_UNIFORMS = ['vSphericalX', 'vSphericalY', 'vSphericalZ', 'vSphericalXX_ZZ', 'vSphericalYY_ZZ',
  'vSphericalZZ', 'vSphericalXY', 'vSphericalYZ', 'vSphericalZX'];
const babylonPolynomialShader = new Function(
  'normal', ...POLY_UNIFORMS, glslToJs(extract(babylonPolynomialText, bodyPattern, 'the polynomial branch')),
);

// Babylon's own uniform binding (BindIBLParameters) with a recording uniform buffer.
function babylonUniforms(polynomial, sphericalHarmonicsDefine) {
  const values = {};
  const ubo = {
    updateMatrix() {}, updateFloat2() {}, updateFloat4() {}, updateColor3() {},
    updateVector3(name, v) { values[name] = [v.x, v.y, v.z]; },
    updateFloat3(name, x, y, z) { values[name] = [x, y, z]; },
  };
  const scene = { texturesEnabled: true, iblIntensity: 1.0 };
  const defines = {
    USEIRRADIANCEMAP: false, USESPHERICALFROMREFLECTIONMAP: true, SPHERICAL_HARMONICS: sphericalHarmonicsDefine,
  };
  const texture = { level: 1.0, sphericalPolynomial: polynomial, getReflectionTextureMatrix: () => null };
  BindIBLParameters(scene, defines, ubo, null, texture, false, false, false, true, true, false, 0);
  return values;
}

function perChannel(shader, normal, uniformNames, values) {
  const out = [];
  for (let c = 0; c < 3; c++) out.push(shader(normal, ...uniformNames.map((n) => values[n][c])));
  return out;
}

function runThree(job) {
  const dirs = job.dirs.map(([x, y, z]) => new Vector3(x, y, z));
  const result = { getAt: [], getIrradianceAt: [], probeShader: [] };
  const target = new Vector3();
  for (const flat of job.sets) {
    const sh = new SphericalHarmonics3().fromArray(flat);
    const probe = new LightProbe(sh, 1.0);
    const lights = new WebGLLights({ has: () => false });
    lights.setup([probe]); // WebGLRenderer's path into the `lightProbe` uniform
    const uniform = lights.state.probe;
    result.getAt.push(dirs.map((d) => probe.sh.getAt(d, target).toArray()));
    result.getIrradianceAt.push(dirs.map((d) => probe.sh.getIrradianceAt(d, target).toArray()));
    result.probeShader.push(dirs.map((d) => [0, 1, 2].map(
      (c) => threeShIrradianceAt(d, uniform.map((v) => v.getComponent(c))),
    )));
  }
  return result;
}

function runBabylon(job) {
  const dirs = job.dirs.map(([x, y, z]) => ({ x, y, z }));
  const result = { harmonicsShader: [], polynomialShader: [], serializedShader: [] };
  for (const flat of job.sets) {
    const rows = HARMONIC_NAMES.map((_, i) => flat.slice(3 * i, 3 * i + 3));
    const polynomial = SphericalPolynomial.FromHarmonics(SphericalHarmonics.FromArray(rows));
    // What a serialized polynomial reloads as: only the nine polynomial terms survive.
    const p = polynomial;
    const serialized = SphericalPolynomial.FromArray(
      [p.x, p.y, p.z, p.xx, p.yy, p.zz, p.yz, p.zx, p.xy].map((v) => [v.x, v.y, v.z]),
    );
    const polyValues = babylonUniforms(polynomial, false);
    const harmValues = babylonUniforms(polynomial, true); // default PBR path (useSphericalHarmonics)
    const serialValues = babylonUniforms(serialized, true);
    result.harmonicsShader.push(dirs.map((d) => perChannel(babylonHarmonicsShader, d, HARMONIC_UNIFORMS, harmValues)));
    result.serializedShader.push(dirs.map((d) => perChannel(babylonHarmonicsShader, d, HARMONIC_UNIFORMS, serialValues)));
    result.polynomialShader.push(dirs.map((d) => perChannel(babylonPolynomialShader, d, POLY_UNIFORMS, polyValues)));
  }
  return result;
}

// skysh's real SH with the Condon-Shortley phase, l <= 2 (docs/conventions.md table), at a unit vector.
const K = [0.5, -Math.sqrt(3) / 2, Math.sqrt(3) / 2, -Math.sqrt(3) / 2, Math.sqrt(15) / 2, -Math.sqrt(15) / 2,
  Math.sqrt(5) / 4, -Math.sqrt(15) / 2, Math.sqrt(15) / 4].map((k) => k / Math.sqrt(Math.PI));
function skyshBasis(x, y, z) {
  const p = [1, y, z, x, x * y, y * z, 3 * z * z - 1, x * z, x * x - y * y];
  return p.map((v, i) => K[i] * v);
}

// Babylon's own cube-map projector (ConvertCubeMapToSphericalPolynomial) on faces that show the
// skysh radiance. Texel directions follow Babylon's face table; the texel centre is sampled.
function runBabylonCubemap(job) {
  const { size, frame } = job;
  const faces = CubeMapToSphericalPolynomialTools._FileFaces;
  const result = { harmonics: [] };
  for (const flat of job.sets) {
    const cube = { size, format: 4, type: 1, gammaSpace: false };
    for (const face of faces) {
      const data = new Float32Array(size * size * 3);
      for (let y = 0; y < size; y++) {
        for (let x = 0; x < size; x++) {
          const u = (x + 0.5) * (2 / size) - 1;
          const v = (y + 0.5) * (2 / size) - 1;
          const d = face.worldAxisForFileX.scale(u).add(face.worldAxisForFileY.scale(v)).add(face.worldAxisForNormal);
          d.normalize();
          const s = [0, 1, 2].map((r) => frame[0][r] * d.x + frame[1][r] * d.y + frame[2][r] * d.z); // frame^T d
          const basis = skyshBasis(s[0], s[1], s[2]);
          for (let c = 0; c < 3; c++) {
            let value = 0;
            for (let i = 0; i < 9; i++) value += flat[3 * i + c] * basis[i];
            data[(y * size + x) * 3 + c] = value;
          }
        }
      }
      cube[face.name] = data;
    }
    const polynomial = CubeMapToSphericalPolynomialTools.ConvertCubeMapToSphericalPolynomial(cube);
    const h = polynomial._harmonics; // the harmonics FromHarmonics was given (A_l / pi times the projection)
    result.harmonics.push(HARMONIC_NAMES.map((n) => [h[n].x, h[n].y, h[n].z]));
  }
  return result;
}

const job = JSON.parse(readFileSync(0, 'utf8'));
const out = {};
if (job.threejs) out.threejs = runThree(job.threejs);
if (job.babylon) out.babylon = runBabylon(job.babylon);
if (job.babylonCubemap) out.babylonCubemap = runBabylonCubemap(job.babylonCubemap);
process.stdout.write(JSON.stringify(out));
