"""
``skysh fit``: fit the Preetham sky's SH coefficients and write the coefficient file
======================================================================================

Projects the sky over a (sun zenith, turbidity) grid (in parallel, with a
progress bar), fits every coefficient with a 2D Chebyshev polynomial by
weighted least squares (skysh.table.fit), fits the sun's direct illuminance
(skysh.model.solar) as ln XYZ in the same run (skysh.table.fit.build_sun), and the
sky's certified non-negative 3-band irradiance (skysh.table.irradiance_fit.build_table:
a convex problem per grid point, the sky table's polynomial, the exact minimum
at 12,004 held-out points; needs the tools extra, cvxpy), measures them on
held-out points and writes a versioned file (skysh.table.coefficient_file, format
version 4). The logic lives in :mod:`skysh.table`; this is the command line. It runs
from an installed package (``pip install "skysh[tools]"`` brings cvxpy; the progress
bar is drawn when tqdm is installed) and from a checkout (``python tools/fit_sky.py``
runs this module too).

    python tools/fit_sky.py --quick --out /tmp/q.npz
    python tools/fit_sky.py --tolerance 1e-3 --out /tmp/small.npz
    python tools/fit_sky.py --compare-scalings --out /tmp/x.npz
    python tools/fit_sky.py --out data/preetham_sh.npz --force   # regenerate the shipped file

The shipped file: ``OPENBLAS_NUM_THREADS=1 python tools/fit_sky.py --out
data/preetham_sh.npz --force --no-progress --workers 2`` (most of its time goes to the
irradiance's 1,316 convex problems; it prints its wall time; same command and tree, same bytes).

``--out`` is required: there is no default file. The shipped coefficient file
(``data/preetham_sh.npz`` of the source tree, ``skysh/data/preetham_sh.npz`` of
the installed package, also through a symlink or hard link) is replaced only
when named with ``--out`` and ``--force`` together; any other file is written
(atomically) whether it exists or not. Every refusal is one line
``<prog>: error: ...`` on stderr with exit status 2.

The irradiance table is a required table of the file format
(``skysh.table.coefficient_file.TABLES``), so without cvxpy every run refuses before
any projection (``--compare-scalings`` too: it also writes the file)::

    fit_sky.py: error: fitting the certified irradiance table needs cvxpy and clarabel (the tools extra), which
    are not installed: pip install -e ".[tools]"
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from pathlib import Path
from typing import Any, NoReturn

# One BLAS thread per process: the pool already uses every core, and oversubscribed
# OpenBLAS threads made small least-squares solves 50x slower on a loaded machine.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import skysh  # noqa: E402
from skysh import files  # noqa: E402
from skysh._version import __version__  # noqa: E402
from skysh.sh import basis as sh  # noqa: E402
from skysh.table import coefficient_file, fit, irradiance_fit, sun_table  # noqa: E402

QUICK_GRID = (16, 8)
QUICK_HELD_OUT = 24
MAX_GRID_NODES: int = fit.MAX_GRID_NODES
"""Largest --grid in either variable (skysh.table.fit's bound)."""
MAX_JOBS: int = 256
"""Largest --jobs."""
SUN_GOAL: float = 1e-4
"""Issue 15's goal for the sun table: worst held-out relative error (skysh.table.fit.SUN_ERROR_DEFINITION)."""
QUICK_IRRADIANCE_HELD_OUT: tuple[int, int] = (8, 1)
"""--quick: exact solves for the irradiance table's fit error (random points, per edge; plus the corners)."""
IRRADIANCE_TASK: str = "fitting the certified irradiance table"
"""What needs cvxpy, in the refusal when it is missing (the table is required by the file format)."""
MAX_SAMPLES: int = 1_000_000
"""Largest --samples: a projection holds about 55 floats per sample at 7 bands (440 MB at the bound) per worker."""


class OneLineParser(argparse.ArgumentParser):
    """argparse whose refusals are one line ``<prog>: error: <message>`` and exit status 2 (no usage block)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())}\n")


def shipped_files() -> list[Path]:
    """The shipped coefficient file of the imported (maybe installed) package and, in a checkout, of its tree."""
    name = coefficient_file.DEFAULT_FILE_NAME
    return [Path(skysh.__file__).resolve().parent / "data" / name] + [d / name for d in files.package_dirs()[1:]]


def is_shipped_file(path: Path) -> bool:
    """Whether ``path`` names a shipped coefficient file (same resolved path, or the same file through a link)."""
    target = path.resolve()
    return any(target == shipped.resolve() or _same_file(path, shipped) for shipped in shipped_files())


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` both exist and are one file (a link, a hard link); False where that cannot be told."""
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def git_commit() -> str:
    """The repository's HEAD (with '+dirty' when the work tree differs), or 'unknown'."""
    checkout = files.package_dirs()[0].parent
    if not (checkout / "pyproject.toml").is_file():
        return "unknown"
    git = partial(subprocess.run, cwd=checkout, capture_output=True, text=True)
    try:
        head = git(["git", "rev-parse", "HEAD"], check=True).stdout.strip()
        dirty = git(["git", "status", "--porcelain", "--untracked-files=no"]).stdout.strip()
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


def check_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse (one line, exit 2) what would fail later or overwrite the shipped file, before any projection."""
    check_out(parser, args)
    if args.colourspace not in coefficient_file.FILE_COLOURSPACES:
        parser.error(f"--colourspace must be one of: {', '.join(coefficient_file.FILE_COLOURSPACES)}; got {args.colourspace!r}")
    check_limits(parser, args)
    if not irradiance_fit.solver_available():  # every file has the irradiance table: refuse before the projections
        parser.error(irradiance_fit.solver_missing_message(IRRADIANCE_TASK))


def check_out(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse a missing ``--out``, the shipped file without ``--force``, or any other of the package's own files."""
    if args.out is None:
        parser.error("--out is required: name the file to write, e.g. --out /tmp/sky.npz (the shipped "
                     "data/preetham_sh.npz is replaced only with --out data/preetham_sh.npz --force)")
    shipped = is_shipped_file(args.out)
    if shipped and not args.force:
        parser.error(f"--out {args.out} is the shipped coefficient file; add --force to replace it")
    try:  # a directory, or any other of the package's own files (modules, the viewer's page), even with --force
        files.check_output(args.out, "--out", may_replace=args.out if shipped else None)
    except (TypeError, ValueError) as error:
        parser.error(str(error))


def check_limits(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse degrees, grid, samples, tolerance or jobs outside what the fit and the file allow."""
    top = coefficient_file.MAX_FILE_DEGREE
    for flag, pair in (("--degrees", args.degrees), ("--sun-degrees", args.sun_degrees)):
        if max(pair) > top:
            parser.error(f"{flag} must be at most {top},{top} (coefficient_file.MAX_FILE_DEGREE), got {pair[0]},{pair[1]}")
    if args.grid is not None and not all(1 <= n <= MAX_GRID_NODES for n in args.grid):
        parser.error(f"--grid must be two integers in [1, {MAX_GRID_NODES}], got {args.grid[0]},{args.grid[1]}")
    if args.samples is not None and not 1 <= args.samples <= MAX_SAMPLES:
        parser.error(f"--samples must be an integer in [1, {MAX_SAMPLES}], got {args.samples}")
    if args.tolerance is not None and not 0 < args.tolerance < 1:
        parser.error(f"--tolerance must lie in (0, 1), got {args.tolerance}")
    if not 1 <= args.jobs <= MAX_JOBS:
        parser.error(f"--jobs must be an integer in [1, {MAX_JOBS}], got {args.jobs}")


def print_sun(sky_table: coefficient_file.SkyTable) -> None:
    """The sun table's held-out errors, as recorded in the file's metadata (tables.sun)."""
    block = sky_table.metadata.get("tables", {}).get("sun")
    if block is None or "errors" not in block:
        return
    errors = block["errors"]
    print(f"\nsun table (ln XYZ, degrees {block['degrees'][0]}, condition number {block['condition_number']:.3g}, largest "
          f"channel sum of |coefficients| {block['largest_abs_sum']:.3g}, file bound {sun_table.SUN_MAX_LN:g}): held-out "
          f"errors on {errors['held_out_points']} points ({block['held_out']['kinds']})")
    print(f"definition: {errors['definition']}")
    print("| sun table | X | Y | Z | R | G | B | worst | goal |")
    print("|---|---|---|---|---|---|---|---|---|")
    cells = " | ".join(f"{v:.2e}" for v in errors["xyz_relative_worst"] + errors["rgb_relative_worst"])
    met = "met" if errors["worst"] <= SUN_GOAL else "NOT met"
    print(f"| worst relative error | {cells} | {errors['worst']:.2e} at {errors['worst_at']} | <= {SUN_GOAL:g}: {met} |")
    print(json.dumps({"fit": "sun", "degrees": block["degrees"], **errors}))


def print_irradiance(sky_table: coefficient_file.SkyTable, seconds: float) -> None:
    """The irradiance table's objective, fit error and certificate, as recorded in the metadata (tables.irradiance)."""
    block = sky_table.metadata["tables"]["irradiance"]
    objective, fit_error, proof = block["objective"], block["fit_error"], block["nonnegativity"]
    degrees = sky_table.tables["irradiance"].degrees[0].tolist()
    print(f"\nirradiance table ({objective['method']}, margin {block['margin']:g}, u'v' <= {objective['chroma']}; degrees "
          f"{degrees}, grid {block['grid']['shape']}, condition number {block['condition_number']:.3g}; solves and "
          f"checks {seconds:.0f} s wall)")
    print("| irradiance table | worst | median | points | certificate: lowest minimum / mean | points negative |")
    print("|---|---|---|---|---|---|")
    print(f"| fit error vs exact optima (max over the sphere / mean) | {fit_error['worst']:.3e} | {fit_error['median']:.3e} "
          f"| {fit_error['points']} | {proof['lowest']:.3e} at {proof['lowest_at']} ({proof['points']} points) | "
          f"{proof['negative']} |")
    print(json.dumps({"fit": "irradiance", "margin": block["margin"], "objective": objective, "fit_error": fit_error,
                      "nonnegativity": proof}))


def build_parser() -> OneLineParser:
    """The command line (``--workers`` is ``--jobs``)."""
    parser = OneLineParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=None, help="output .npz (required; the shipped file only with --force)")
    parser.add_argument("--force", action="store_true", help="allow --out to name the shipped data/preetham_sh.npz")
    parser.add_argument("--bands", type=int, default=7, choices=range(1, 8), metavar="{1..7}", help="SH bands to fit (default 7)")
    parser.add_argument("--degrees", type=parse_pair, default=(13, 7), help="polynomial degrees 'd_theta,d_tau' (default 13,7); "
                        "the upper limit with --tolerance")
    parser.add_argument("--sun-degrees", type=parse_pair, default=(12, 6), help="degrees 'd_x,d_y' of the sun table (default "
                        "12,6)")
    parser.add_argument("--grid", type=parse_pair, default=None, help="grid nodes 'n_theta,n_tau' (default 48,24; --quick 16,8)")
    parser.add_argument("--colourspace", default="sRGB", help="RGB colourspace, one of: "
                        f"{', '.join(coefficient_file.FILE_COLOURSPACES)} (default sRGB)")
    parser.add_argument("--method", default="quadrature", choices=sh.PROJECTION_METHODS, help="projection method (default: the "
                        "sun-adapted quadrature)")
    parser.add_argument("--samples", type=int, default=None, help="samples per projection (default: the method's default)")
    parser.add_argument("--tolerance", type=float, default=None, help="choose the smallest degrees per band whose worst "
                        "validation E_mean stays within this fraction (e.g. 1e-3)")
    parser.add_argument("--quick", action="store_true", help=f"tiny grid {QUICK_GRID} and {QUICK_HELD_OUT} held-out points (for "
                        "tests)")
    parser.add_argument("--jobs", "--workers", type=int, default=os.cpu_count() or 1, help="worker processes (default: all "
                        "cores)")
    parser.add_argument("--compare-scalings", action="store_true", help="also print the held-out error of the fit's variable and "
                        "scale choices")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def with_irradiance(parser: argparse.ArgumentParser, args: argparse.Namespace, sky_table: coefficient_file.SkyTable,
                    grid: tuple[int, int], mapper: Any) -> coefficient_file.SkyTable:
    """``sky_table`` with the irradiance table of :func:`skysh.table.irradiance_fit.build_table` and its block (exit 2 if
    it is not certified non-negative)."""
    held_out = QUICK_IRRADIANCE_HELD_OUT if args.quick else irradiance_fit.FIT_ERROR_POINTS
    try:
        table, degrees, block = irradiance_fit.build_table(grid, args.degrees, irradiance_fit.RECOMMENDED,
                                                           args.colourspace, mapper, held_out)
    except RuntimeError as error:  # not certified non-negative: no file
        parser.error(f"the irradiance table: {error}")
    return coefficient_file.SkyTable(
        sky_table.table, sky_table.degrees,
        {**sky_table.metadata, "tables": {**sky_table.metadata["tables"], "irradiance": block}},
        {**sky_table.tables, "irradiance": coefficient_file.NamedTable(table, degrees)})


class _NoBar:
    """A progress bar that draws nothing (``--no-progress``, or tqdm not installed)."""

    def update(self, n: int) -> None:
        """Nothing to draw."""

    def set_description(self, text: str) -> None:
        """Nothing to draw."""

    def close(self) -> None:
        """Nothing to close."""


def _progress(total: int, disabled: bool) -> Any:
    """tqdm's bar on stderr when it is installed and wanted, else :class:`_NoBar`."""
    try:
        from tqdm import tqdm
    except ModuleNotFoundError:
        return _NoBar()
    return tqdm(total=total, desc="projecting the sky", unit="sky", disable=disabled, file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """``skysh fit``'s command line: parse ``argv``, fit, write ``--out``, print the errors; the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    check_arguments(parser, args)
    grid = args.grid or (QUICK_GRID if args.quick else (48, 24))
    settings = fit.FitSettings(bands=args.bands, degrees=args.degrees, grid=grid, colourspace=args.colourspace,
                               method=args.method, samples=args.samples, held_out=QUICK_HELD_OUT if args.quick else 256,
                               validation=16 if args.quick else 128, sun_degrees=args.sun_degrees)
    irradiance_held_out = QUICK_IRRADIANCE_HELD_OUT if args.quick else irradiance_fit.FIT_ERROR_POINTS
    total = grid[0] * grid[1] + settings.held_out + 4 + (settings.validation + 4 + 24 if args.tolerance else 0)
    total += grid[0] * grid[1] + irradiance_held_out[0] + 4 + 4 * irradiance_held_out[1]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        bar = _progress(total, args.no_progress)

        def mapper(function, jobs):
            for result in pool.map(function, jobs, chunksize=8):
                bar.update(1)
                yield result

        command = "python tools/fit_sky.py " + " ".join(argv if argv is not None else sys.argv[1:])
        provenance = {"package_version": __version__, "git_commit": git_commit(), "command": command}
        sky_table, report, samples = fit.build(settings, tolerance=args.tolerance, mapper=mapper, provenance=provenance)
        bar.set_description("the irradiance's convex problems")
        irradiance_start = time.perf_counter()
        sky_table = with_irradiance(parser, args, sky_table, grid, mapper)
        bar.close()
    try:
        path = coefficient_file.write(args.out, sky_table)
    except (ValueError, OSError) as error:  # CoefficientFileError is a ValueError; an unwritable --out
        parser.error(f"cannot write --out {args.out}: {error}")
    elapsed = time.perf_counter() - start
    print(f"wrote {path} ({path.stat().st_size / 1024:.1f} KiB) in {elapsed:.1f} s; degrees per band "
          f"{sky_table.degrees.tolist()}, condition number {sky_table.metadata['condition_number']:.3g}, largest |table "
          f"value| {float(abs(sky_table.table).max()):.3g} (file bound {coefficient_file.MAX_TABLE_MAGNITUDE:g})")
    print(f"held-out errors ({report['held_out_points']} points incl. the 4 corners; fractions of L_min, worst channel):")
    print("| bands | worst E_mean (eq. 3) | mean E_mean | worst E_max (eq. 2) | worst DC error |")
    print("|---|---|---|---|---|")
    for bands, row in report["by_bands"].items():
        print(f"| {bands} | {row['e_mean_worst']:.2e} | {row['e_mean_mean']:.2e} | {row['e_max_worst']:.2e} | "
              f"{row['dc_worst']:.2e} |")
    print(json.dumps({"fit": "summary", "elapsed_s": elapsed, "degrees": sky_table.degrees.tolist(), **report}))
    print_sun(sky_table)
    print_irradiance(sky_table, time.perf_counter() - irradiance_start)
    if args.compare_scalings:
        print("\nform of the fit (same projections, same held-out points):")
        print(f"| form | condition | worst E_mean 3 bands | worst E_mean {args.bands} bands |")
        print("|---|---|---|---|")
        for row in fit.compare_variants(samples, args.degrees, args.bands):
            print(f"| {row['variant']} | {row['condition']:.3g} | {row[f'e_mean_worst_{min(3, args.bands)}']:.2e} | "
                  f"{row[f'e_mean_worst_{args.bands}']:.2e} |")
            print(json.dumps({"fit": "variant", **row}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
