"""
Per-call cost of the JavaScript module against the C export
===========================================================

The JS module (:func:`skysh.export.js.module_source`, node) and the C header
(:func:`skysh.export.c_like.export_source`, double, compiled with ``-O2``) evaluate the
same calls, side by side in one run: the same random (sun zenith, turbidity,
azimuth) inputs, a loop timed inside each language (``process.hrtime`` and
``clock_gettime(CLOCK_MONOTONIC)``), a checksum of every result kept so that no
call is optimised away, and each language's checksum compared with the other's
(they evaluate the same arithmetic: equal to about 1e-15 relative).

Cases (each: ns per call in both languages and the ratio JS / C):

-   ``radiance-3``: 3 bands, Gibbs filter (the radiance default);
-   ``irradiance-3``: 3 bands, irradiance, no Gibbs filter;
-   ``irradiance-dering-3``: the same with deringing (the irradiance defaults);
-   ``radiance-7``: 7 bands;
-   ``out-3``: JS only differs: the result written into a preallocated ``out``;
-   ``engine-<name>-3``: the first engine of :mod:`skysh.engines.presets` (when it exists).

Timings are wall time: each process times one round of ``--calls`` calls after
a warm-up round, C and JS processes take turns ``--repeats`` times (so both
see the same load) and the best round of each is kept. On a loaded machine run
it a few times. The script prints one JSON object per line and always exits 0
(no target is enforced; the issue asks for the figure).

Run: ``PYTHONPATH=. python benchmarks/bench_js.py [--calls 20000] [--repeats 5]``.
``benchmarks/bench_js_floor.py`` times the module against a hand-written JavaScript floor instead.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from skysh import SkySH
from skysh.export.c_like import export_source
from skysh.export.js import module_source

C_HARNESS: str = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "sky_sh.h"

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    int n, repeats = atoi(argv[1]), gibbs = atoi(argv[2]), irradiance = atoi(argv[3]), engine = atoi(argv[4]);
    int dering = atoi(argv[5]);
    int i, k, r, c;
    double *in, best = 1e300, sum = 0.0;
    if (scanf("%d", &n) != 1) return 1;
    in = malloc(sizeof(double) * 3 * (size_t)n);
    for (i = 0; i < 3 * n; ++i)
        if (scanf("%lf", &in[i]) != 1) return 1;
    for (r = 0; r <= repeats; ++r) { /* round 0 warms up */
        double start = now(), check = 0.0;
        for (i = 0; i < n; ++i) {
#ifdef SKYSH_ENGINE_COUNT
            if (engine) {
                skysh_real e[SKYSH_ENGINE_COUNT];
                skysh_engine_coefficients(in[3 * i], in[3 * i + 1], in[3 * i + 2], gibbs, dering, 0, NULL, SKYSH_BY_INTENT, e);
                for (k = 0; k < SKYSH_ENGINE_COUNT; ++k) check += e[k];
                continue;
            }
#endif
            {
                skysh_real out[SKYSH_COUNT][3];
                skysh_coefficients(in[3 * i], in[3 * i + 1], in[3 * i + 2], gibbs, dering, irradiance, 0, NULL,
                                   SKYSH_BY_INTENT, out);
                for (k = 0; k < SKYSH_COUNT; ++k)
                    for (c = 0; c < 3; ++c) check += out[k][c];
            }
        }
        {
            const double elapsed = now() - start;
            if (r > 0 && elapsed < best) best = elapsed;
        }
        sum = check;
    }
    (void)engine;
    printf("{\"seconds_per_call\": %.9g, \"checksum\": %.17g}\n", best / n, sum);
    free(in);
    return 0;
}
"""

JS_HARNESS: str = r"""
import { readFileSync } from "node:fs";
import { pathToFileURL } from "node:url";
const [moduleFile, inputFile, repeatsText, optionsText] = process.argv.slice(2);
const { coefficients } = await import(pathToFileURL(moduleFile).href);
const input = Float64Array.from(JSON.parse(readFileSync(inputFile, "utf8")));
const options = JSON.parse(optionsText);
const n = input.length / 3;
if (options.out) options.out = new Float64Array(coefficients(0.5, 3, 0, { ...options, out: undefined }).length);
let best = Infinity, sum = 0;
for (let r = 0; r <= Number(repeatsText); r++) { // round 0 warms up (and lets the JIT compile)
  const start = process.hrtime.bigint();
  let check = 0;
  for (let i = 0; i < n; i++) {
    const c = coefficients(input[3 * i], input[3 * i + 1], input[3 * i + 2], options);
    for (let k = 0; k < c.length; k++) check += c[k];
  }
  const seconds = Number(process.hrtime.bigint() - start) * 1e-9;
  if (r > 0 && seconds < best) best = seconds;
  sum = check;
}
process.stdout.write(JSON.stringify({ seconds_per_call: best / n, checksum: sum }) + "\n");
"""


def inputs(calls: int, seed: int = 7) -> np.ndarray:
    """(calls, 3) random sun zenith [0, pi/2], turbidity [2.5, 6], azimuth [-pi, pi]."""
    rng = np.random.default_rng(seed)
    return np.column_stack([
        rng.uniform(0.0, math.pi / 2.0, calls), rng.uniform(2.5, 6.0, calls), rng.uniform(-math.pi, math.pi, calls),
    ])


def compile_c(directory: Path, source: str, name: str) -> Path:
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise SystemExit("no C compiler")
    folder = directory / name
    folder.mkdir()
    (folder / "sky_sh.h").write_text(source)
    (folder / "bench.c").write_text(C_HARNESS)
    binary = folder / "bench"
    subprocess.run([cc, "-std=c99", "-O2", "-o", str(binary), str(folder / "bench.c"), "-lm"], check=True)
    return binary


def run_c(binary: Path, points: np.ndarray, repeats: int, flags: tuple[bool, bool, bool, bool]) -> dict:
    """Time the C harness; flags = (gibbs, irradiance, engine, dering)."""
    text = f"{len(points)}\n" + "\n".join(" ".join(repr(float(v)) for v in row) for row in points) + "\n"
    args = [str(binary), str(repeats), *(str(int(f)) for f in flags)]
    return json.loads(subprocess.run(args, input=text, capture_output=True, text=True, check=True).stdout)


def run_js(node: str, directory: Path, points_file: Path, repeats: int, options: dict[str, Any]) -> dict:
    args = [node, str(directory / "bench.mjs"), str(directory / "sky_sh.mjs"), str(points_file), str(repeats),
            json.dumps(options)]
    return json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--calls", type=int, default=20000, help="calls per timed round (default 20000)")
    parser.add_argument("--repeats", type=int, default=5, help="timed rounds per language, alternating, best kept (default 5)")
    args = parser.parse_args()
    node = shutil.which("node")
    if node is None:
        raise SystemExit("node is not installed")
    sky = SkySH.load()
    points = inputs(args.calls)
    try:
        from skysh.engines import presets as engines

        engine = engines.ENGINES[0]
    except ModuleNotFoundError:
        engine = None
    # (label, bands, gibbs, irradiance, dering, engine, out)
    cases: list[tuple[str, int, bool, bool, bool, str | None, bool]] = [
        ("radiance-3", 3, True, False, False, None, False), ("irradiance-3", 3, False, True, False, None, False),
        ("irradiance-dering-3", 3, False, True, True, None, False), ("radiance-7", 7, True, False, False, None, False),
        ("out-3", 3, True, False, False, None, True),
    ]
    if engine is not None:
        cases.append((f"engine-{engine}-3", 3, False, False, False, engine, False))
    print(json.dumps({"machine": platform.machine(), "node": subprocess.run([node, "--version"], capture_output=True, check=True,
                      text=True).stdout.strip(), "calls": args.calls, "repeats": args.repeats}))
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        (directory / "sky_sh.mjs").write_text(module_source(sky))
        (directory / "bench.mjs").write_text(JS_HARNESS)
        points_file = directory / "points.json"
        points_file.write_text(json.dumps(points.ravel().tolist()))
        for label, bands, gibbs, irradiance, dering, engine_name, out in cases:
            binary = compile_c(directory, export_source(sky, "c", bands=bands, engine=engine_name), label)
            options: dict[str, Any] = {"bands": bands, "gibbs": gibbs, "irradiance": irradiance, "dering": dering}
            if engine_name is not None:
                options = {"bands": bands, "gibbs": gibbs, "dering": dering, "engine": engine_name}
            if out:
                options["out"] = True
            c_runs, js_runs = [], []
            for _ in range(args.repeats):  # alternate, so both languages see the same load
                c_runs.append(run_c(binary, points, 1, (gibbs, irradiance, engine_name is not None, dering)))
                js_runs.append(run_js(node, directory, points_file, 1, options))
            c = min(c_runs, key=lambda run: run["seconds_per_call"])
            js = min(js_runs, key=lambda run: run["seconds_per_call"])
            print(json.dumps({
                "bench": label, "js_ns_per_call": round(js["seconds_per_call"] * 1e9, 1),
                "c_ns_per_call": round(c["seconds_per_call"] * 1e9, 1),
                "ratio_js_over_c": round(js["seconds_per_call"] / c["seconds_per_call"], 2),
                "checksums_agree": abs(js["checksum"] - c["checksum"]) <= 1e-12 * abs(c["checksum"]),
            }))


if __name__ == "__main__":
    main()
