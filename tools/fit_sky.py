#!/usr/bin/env python
"""
Fit the Preetham sky's SH coefficients and write the coefficient file.

Projects the sky over a (sun zenith, turbidity) grid (in parallel, with a
progress bar), fits every coefficient with a 2D Chebyshev polynomial by
weighted least squares (skysh.fit), measures the fit on held-out points and
writes a versioned file (skysh.coefficient_file). The logic lives in the
package; this is the command line.

    python tools/fit_sky.py                      # the shipped data/preetham_sh.npz
    python tools/fit_sky.py --quick --out /tmp/q.npz
    python tools/fit_sky.py --tolerance 1e-3 --out /tmp/small.npz
    python tools/fit_sky.py --compare-scalings --out /tmp/x.npz
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

# One BLAS thread per process: the pool already uses every core, and oversubscribed
# OpenBLAS threads made small least-squares solves 50x slower on a loaded machine.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from skysh import coefficient_file, fit, sh  # noqa: E402
from skysh._version import __version__  # noqa: E402

QUICK_GRID = (16, 8)
QUICK_HELD_OUT = 24


def git_commit() -> str:
    """The repository's HEAD (with '+dirty' when the work tree differs), or 'unknown'."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
        return head + ("+dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def parse_pair(text: str) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two integers 'A,B', got {text!r}") from None
    if a < 0 or b < 0:
        raise argparse.ArgumentTypeError(f"expected non-negative integers, got {text!r}")
    return a, b


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=ROOT / "data" / coefficient_file.DEFAULT_FILE_NAME, help="output .npz (default: the shipped file)")
    parser.add_argument("--bands", type=int, default=7, choices=range(1, 8), metavar="{1..7}", help="SH bands to fit (default 7)")
    parser.add_argument("--degrees", type=parse_pair, default=(13, 7), help="polynomial degrees 'd_theta,d_tau' (default 13,7); the upper limit with --tolerance")
    parser.add_argument("--grid", type=parse_pair, default=None, help="grid nodes 'n_theta,n_tau' (default 48,24; --quick 16,8)")
    parser.add_argument("--colourspace", default="sRGB", help="colour-science RGB colourspace name (default sRGB)")
    parser.add_argument("--method", default="quadrature", choices=sh.PROJECTION_METHODS, help="projection method (default: the sun-adapted quadrature)")
    parser.add_argument("--samples", type=int, default=None, help="samples per projection (default: the method's default)")
    parser.add_argument("--tolerance", type=float, default=None, help="choose the smallest degrees per band whose worst validation E_mean stays within this fraction (e.g. 1e-3)")
    parser.add_argument("--quick", action="store_true", help=f"tiny grid {QUICK_GRID} and {QUICK_HELD_OUT} held-out points (for tests)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes (default: all cores)")
    parser.add_argument("--compare-scalings", action="store_true", help="also print the held-out error of the fit's variable and scale choices")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.samples is not None and args.samples < 1:
        parser.error("--samples must be a positive integer")
    if args.tolerance is not None and not 0 < args.tolerance < 1:
        parser.error("--tolerance must lie in (0, 1)")
    grid = args.grid or (QUICK_GRID if args.quick else (48, 24))
    settings = fit.FitSettings(
        bands=args.bands, degrees=args.degrees, grid=grid, colourspace=args.colourspace, method=args.method,
        samples=args.samples, held_out=QUICK_HELD_OUT if args.quick else 256,
        validation=16 if args.quick else 128,
    )
    try:
        from skysh.preetham import rgb_from_xyz_matrix

        rgb_from_xyz_matrix(args.colourspace)
    except ValueError as error:
        parser.error(str(error))

    from tqdm import tqdm

    total = grid[0] * grid[1] + settings.held_out + 4 + (settings.validation + 4 + 24 if args.tolerance else 0)
    start = time.perf_counter()
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        bar = tqdm(total=total, desc="projecting the sky", unit="sky", disable=args.no_progress, file=sys.stderr)

        def mapper(function, jobs):
            for result in pool.map(function, jobs, chunksize=8):
                bar.update(1)
                yield result

        provenance = {
            "package_version": __version__,
            "git_commit": git_commit(),
            "command": "python tools/fit_sky.py " + " ".join(argv if argv is not None else sys.argv[1:]),
        }
        sky_table, report, samples = fit.build(settings, tolerance=args.tolerance, mapper=mapper, provenance=provenance)
        bar.close()
    path = coefficient_file.write(args.out, sky_table)
    elapsed = time.perf_counter() - start
    print(f"wrote {path} ({path.stat().st_size / 1024:.1f} KiB) in {elapsed:.1f} s; degrees per band {sky_table.degrees.tolist()}, "
          f"condition number {sky_table.metadata['condition_number']:.3g}")
    print(f"held-out errors ({report['held_out_points']} points incl. the 4 corners; fractions of L_min, worst channel):")
    print("| bands | worst E_mean (eq. 3) | mean E_mean | worst E_max (eq. 2) | worst DC error |")
    print("|---|---|---|---|---|")
    for bands, row in report["by_bands"].items():
        print(f"| {bands} | {row['e_mean_worst']:.2e} | {row['e_mean_mean']:.2e} | {row['e_max_worst']:.2e} | {row['dc_worst']:.2e} |")
    print(json.dumps({"fit": "summary", "elapsed_s": elapsed, "degrees": sky_table.degrees.tolist(), **report}))
    if args.compare_scalings:
        print("\nform of the fit (same projections, same held-out points):")
        print("| form | condition | worst E_mean 3 bands | worst E_mean %d bands |" % args.bands)
        print("|---|---|---|---|")
        for row in fit.compare_variants(samples, args.degrees, args.bands):
            print(f"| {row['variant']} | {row['condition']:.3g} | {row[f'e_mean_worst_{min(3, args.bands)}']:.2e} | {row[f'e_mean_worst_{args.bands}']:.2e} |")
            print(json.dumps({"fit": "variant", **row}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
