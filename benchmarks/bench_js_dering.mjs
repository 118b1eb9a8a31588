// Cost per call of the JavaScript module's deringing (issue 25), node.
//
// Write the module first, then time it:
//   PYTHONPATH=. python -c "from skysh import SkySH; from skysh.export.js import module_source; \
//     open('/tmp/sky_sh.mjs', 'w').write(module_source(SkySH.load()))"
//   node benchmarks/bench_js_dering.mjs /tmp/sky_sh.mjs [calls = 2000] [repeats = 5]
//
// Per band count 1..7, the same random frames (sun zenith, turbidity, azimuth; a fixed seed) evaluated as irradiance
// with deringing (irradianceTable: false, so 3 bands dering too) and without it; the deringing's cost per call is
// the difference of the two (best round of each of `repeats`, after a warm-up round that also builds the 5..7-band
// certificate's grid). The first call with deringing at 7 bands in a fresh module (the grid's build) is timed apart.
// Prints one JSON line per band count; no target is enforced.
import { pathToFileURL } from "node:url";

const [path, calls = "2000", repeats = "5"] = process.argv.slice(2);
if (!path) throw new Error("usage: node bench_js_dering.mjs MODULE.mjs [calls] [repeats]");
const url = pathToFileURL(path).href;
const fresh = await import(`${url}?fresh`);
let started = performance.now();
fresh.coefficients(0.5, 3.0, 1.0, { bands: 7, irradiance: true });
const firstMs = performance.now() - started;
const m = await import(url);

let seed = 12345;
const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
const frames = Array.from({ length: Number(calls) }, () => [random() * Math.PI / 2, 2.5 + 3.5 * random(), 6 * random()]);

function round(options) {
  let checksum = 0.0;
  const start = performance.now();
  for (const [ts, t, phi] of frames) checksum += m.coefficients(ts, t, phi, options)[0];
  return [(performance.now() - start) * 1000 / frames.length, checksum];
}

function best(options) {
  round(options); // warm-up
  let low = Infinity;
  for (let r = 0; r < Number(repeats); r++) low = Math.min(low, round(options)[0]);
  return low;
}

for (let bands = 1; bands <= 7; bands++) {
  const base = { bands, irradiance: true, irradianceTable: false };
  const withDering = best({ ...base, dering: true }), without = best({ ...base, dering: false });
  console.log(JSON.stringify({ bands, calls: frames.length, us_per_call_deringed: withDering, us_per_call_plain: without,
    us_dering_per_call: withDering - without, ...(bands === 7 ? { first_call_ms_7: firstMs } : {}) }));
}
