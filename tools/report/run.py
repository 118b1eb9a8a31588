"""
The report's command line: choose sections, run them, write report.md
======================================================================

:data:`SECTIONS` maps each section number to its module; a module has ``NUMBER``,
``TITLE``, ``compute(ctx) -> dict`` (plain data) and ``render(ctx, data) ->
Section`` (markdown, figures, summary rows). A section that raises stops the run
with its traceback: nothing is turned into "not measured".

A section that needs an optional package of the tools extra names it: its module's
``missing_packages() -> tuple[str, ...]`` (:data:`MISSING_PACKAGES`) returns those not
installed here. Before any section runs, every chosen section is asked; one that lacks
a package is skipped, said so on stderr, in its own heading's place, in the summary
table and in the section list (the package, the extra, :data:`INSTALL`), and the rest
of the report completes (exit 0). Nothing else is skipped: a section that raises still
stops the run.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from types import ModuleType

import numpy as np

import skysh
from report import (
    s01_projection,
    s02_fit,
    s03_speed,
    s04_gibbs,
    s05_dering,
    s06_quantization,
    s07_irradiance,
    s08_stability,
    s09_scene,
    s10_pictures,
    s11_irradiance_table,
    s12_scene_irradiance,
    s13_hosek,
)
from report.common import Context, Section, markdown_table, sig
from report.plans import FULL, QUICK
from skysh.app import fit_command  # the commit stamp of a run (skysh fit writes it too)
from skysh.app.argtypes import integer
from skysh.runtime import SkySH
from skysh.table import irradiance_fit

SECTIONS: dict[int, ModuleType] = {
    m.NUMBER: m
    for m in (s01_projection, s02_fit, s03_speed, s04_gibbs, s05_dering, s06_quantization, s07_irradiance,
              s08_stability, s09_scene, s10_pictures, s11_irradiance_table, s12_scene_irradiance, s13_hosek)
}
"""Report sections in order; each computes its data, then renders it."""

SECTION_TITLES: dict[int, str] = {k: m.TITLE for k, m in SECTIONS.items()}
"""Headings of report.md (``## k. title``)."""

MISSING_PACKAGES: str = "missing_packages"
"""Name of a section module's optional ``() -> tuple[str, ...]``: the packages it needs that are not installed."""

EXTRA: str = irradiance_fit.SOLVER_EXTRA
"""The extra that brings every optional package a section may need (cvxpy and Clarabel: section 11)."""

INSTALL: str = irradiance_fit.SOLVER_INSTALL
"""The command that installs :data:`EXTRA`."""

DEFAULT_JOBS: int = 2
"""Worker processes for the sky projections by default (the machine's 2 cores)."""

DESCRIPTION: str = "The skysh error report: every accuracy, cost and stability figure in one run."


def parse_sections(text: str) -> list[int]:
    """``"1,3,8"`` -> [1, 3, 8]; an unknown or malformed number is a usage error."""
    try:
        chosen = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected section numbers like '1,3,8', got {text!r}") from None
    if not chosen or any(k not in SECTIONS for k in chosen):
        raise argparse.ArgumentTypeError(f"sections must be among 1..{len(SECTIONS)}, got {text!r}")
    return chosen


def build_parser() -> argparse.ArgumentParser:
    epilog = "sections:\n" + "\n".join(f"  {k:2d}. {t}" for k, t in SECTION_TITLES.items())
    parser = argparse.ArgumentParser(description=DESCRIPTION, epilog=epilog,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True, help="output directory (report.md and PNGs)")
    parser.add_argument("--quick", action="store_true", help="small sizes: well under a minute (the test suite's run)")
    parser.add_argument("--jobs", type=integer(), default=DEFAULT_JOBS,
                        help=f"worker processes for the sky projections (default {DEFAULT_JOBS})")
    parser.add_argument("--sections", type=parse_sections, default=list(SECTIONS), help="only these sections, e.g. '1,3'")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    return parser


def run_section(ctx: Context, number: int) -> Section:
    """Compute one section's data, then render it."""
    module = SECTIONS[number]
    return module.render(ctx, module.compute(ctx))


def missing_packages(number: int) -> tuple[str, ...]:
    """The optional packages section ``number`` needs that are not installed (its module's :data:`MISSING_PACKAGES`
    function; none if it has none)."""
    ask = getattr(SECTIONS[number], MISSING_PACKAGES, None)
    return () if ask is None else tuple(ask())


def skip_reason(missing: tuple[str, ...], code: str = "`") -> str:
    """Why a section is skipped: its missing packages, their extra and the install command (each within ``code``:
    markdown's backquote, or "" for the terminal)."""
    names = " and ".join(missing)
    verb = "is" if len(missing) == 1 else "are"
    return f"needs {names} (the {code}{EXTRA}{code} extra), which {verb} not installed: {code}{INSTALL}{code}"


def skipped_section(ctx: Context, number: int, missing: tuple[str, ...]) -> Section:
    """The heading of a section skipped for ``missing`` packages, what to install and how to run it then."""
    s = Section(number, SECTION_TITLES[number])
    s.text(f"**Skipped in this run**: this section {skip_reason(missing)}. Install the extra and run the report "
           f"again (`--sections {number}` for this section alone, into another `--out`: a run replaces its folder's "
           "report and charts).")
    ctx.note(f"Section {number}. {SECTION_TITLES[number]}", f"skipped: {skip_reason(missing)}", "")
    return s


def header(args: argparse.Namespace, ctx: Context, elapsed: float, timings: list[tuple[int, float]],
           skipped: dict[int, tuple[str, ...]]) -> list[str]:
    """The report's title, provenance, summary table, section links (skipped ones marked) and time per section."""
    links = ", ".join(f"[{k}. {SECTION_TITLES[k]}](#{k}-{SECTION_TITLES[k].lower().replace(' ', '-')})"
                      + (f" (skipped: needs {' and '.join(skipped[k])})" if k in skipped else "")
                      for k in args.sections)
    return [
        "# skysh error report",
        "",
        (f"Generated by `python tools/error_report.py --out {args.out.as_posix()}{' --quick' if args.quick else ''}` "
         f"({ctx.plan.name} run) in {sig(elapsed)} s: skysh {skysh.__version__}, commit {fit_command.git_commit()}, "
         f"Python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, {ctx.jobs} worker "
         "processes. Every number below was computed in this run; quoted figures of the seed papers are labelled as "
         "such. Timings come from a shared machine (best of several runs) and vary between runs. Errors are "
         "fractions shown as percentages; E_mean and E_max are Habel 2008's eqs. 3 and 2 (sum over the coefficients "
         "of the bands used, divided by L_min, the sky's minimum over the upper hemisphere per channel, worst "
         "channel)."),
        "",
        "## Summary",
        "",
        *markdown_table(["quantity", "this run", "seed (Habel et al. 2008 unless noted)"], ctx.summary),
        "Sections: " + links,
        "",
        "Time per section: " + ", ".join(f"{k}: {'skipped' if k in skipped else f'{sig(t)} s'}" for k, t in timings),
        "",
    ]


def main(argv: list[str] | None = None) -> int:
    """Run the chosen sections and write ``OUT/report.md`` and its PNGs; 0 on success (a failing section raises; one
    lacking an optional package is skipped, said on stderr and in the report)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    skipped = {k: m for k in args.sections if (m := missing_packages(k))}  # before any work
    for number, missing in skipped.items():
        print(f"{parser.prog}: section {number} ({SECTION_TITLES[number]}) skipped: {skip_reason(missing, '')}",
              file=sys.stderr)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("s[0-9][0-9]_*.png"):
        old.unlink()  # stale charts of an earlier run
    start = time.perf_counter()
    plan = QUICK if args.quick else FULL
    ctx = Context(plan=plan, out=out, jobs=args.jobs, progress=not args.no_progress, sky=SkySH.load())
    sections, timings = [], []
    with ctx.bar(len(args.sections), "error report") as bar:
        for number in args.sections:
            t0 = time.perf_counter()
            sections.append(skipped_section(ctx, number, skipped[number]) if number in skipped
                            else run_section(ctx, number))
            timings.append((number, time.perf_counter() - t0))
            bar.update(1)
    elapsed = time.perf_counter() - start
    ctx.note("Report run time (this run)", f"{sig(elapsed)} s ({plan.name}, {ctx.jobs} processes)", "")
    body = [line for sec in sections for line in sec.lines]
    (out / "report.md").write_text("\n".join(header(args, ctx, elapsed, timings, skipped) + body).rstrip() + "\n",
                                   encoding="utf-8")
    size = sum((out / name).stat().st_size for name in ctx.figures)
    print(f"wrote {out / 'report.md'} and {len(ctx.figures)} PNGs ({size / 1e6:.2f} MB) in {elapsed:.1f} s"
          + (f"; skipped sections {', '.join(map(str, skipped))} (missing {EXTRA} extra: {INSTALL})" if skipped else ""))
    return 0
