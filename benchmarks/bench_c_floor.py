"""
The C export's per-call cost against a hand-written floor
=========================================================

The C header (:func:`skysh.export.c_like.export_source`, double) against ``benchmarks/c_floor.c``, the least
hand-written C for the same arithmetic over the same header's tables (issue 26), both built with the machine's
C compiler at each of :data:`LEVELS` and run in one process: alternating rounds of each (the order swapped
round by round), each round timed by the thread's CPU clock (``clock_gettime(CLOCK_THREAD_CPUTIME_ID)``), the
median round kept. Before timing, the floor's coefficients are checked against the export's on every frame
(``max_diff_over_dc``: the largest difference over |DC| of the same channel; about 1e-15 when they agree).

Cases (:data:`CASES`), at 3 and 7 bands: ``radiance`` (the Gibbs filter), ``irradiance`` (no Gibbs filter, no
deringing), ``lit`` (radiance with the sun and a 0.2 grey ground), ``irradiance-default`` (deringing asked, the
runtime's default: 3 bands take the certified table, which the floor evaluates too; 7 bands dering, which it does
not: export only). Then ``growth``: the export's radiance per call at 1..7 bands against the size of its table.

Prints the environment (load average included), then one JSON object per line and always exits 0 (no target is
enforced; issue 26 asks for the export within 1.2x of the floor). ``--export-from DIR``: the export's header
written by another checkout's ``skysh`` (e.g. ``git worktree add /tmp/before HEAD``), timed against this
checkout's floor: the figures before a change.

Run: ``PYTHONPATH=. python benchmarks/bench_c_floor.py [--calls 2000] [--rounds 21] [--export-from DIR]``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from _timing import environment

from skysh import SkySH
from skysh.export.c_like import export_source
from skysh.export.tables import export_tables

FLOOR_SOURCE: Path = Path(__file__).resolve().parent / "c_floor.c"
"""The floor and the timing program (its ``main`` prints one JSON object per case)."""

LEVELS: dict[str, list[str]] = {"O2": ["-O2"], "O3-native": ["-O3", "-march=native"]}
"""The optimisation levels both are built at (C99, as the export tests build the header)."""

CASES: dict[str, int] = {"radiance": 0, "irradiance": 1, "lit": 2, "irradiance-default": 3}
"""The cases of ``c_floor.c`` (its ``main``'s first argument)."""

BANDS: tuple[int, ...] = (3, 7)
"""The band counts of the cases."""

GROWTH_BANDS: tuple[int, ...] = tuple(range(1, 8))
"""The band counts of the growth line (radiance)."""


def header(bands: int, export_from: Path | None) -> str:
    """The double C header of ``bands`` bands, from this checkout or (``export_from``) another's ``skysh``."""
    if export_from is None:
        return export_source(SkySH.load(), "c", bands=bands)
    code = f"from skysh import SkySH; from skysh.export.c_like import export_source; import sys; " \
           f"sys.stdout.write(export_source(SkySH.load(), 'c', bands={bands}))"
    env = dict(os.environ, PYTHONPATH=str(export_from))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env,
                          cwd=export_from).stdout


def build(folder: Path, export_header: str, floor_header: str, flags: list[str]) -> Path:
    """The program: ``c_floor.c`` built twice (the export's unit over ``export_header``, the floor's over
    ``floor_header``) and linked."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise SystemExit("no C compiler")
    folder.mkdir(parents=True)
    (folder / "export.h").write_text(export_header)
    (folder / "floor.h").write_text(floor_header)
    for unit, name, extra in (("export", "export.h", ["-DFLOOR_EXPORT_UNIT"]), ("floor", "floor.h", [])):
        subprocess.run([cc, "-std=c99", *flags, *extra, f'-DSKYSH_HEADER="{folder / name}"', "-c", str(FLOOR_SOURCE),
                        "-o", str(folder / f"{unit}.o")], check=True)
    binary = folder / "bench"
    subprocess.run([cc, str(folder / "export.o"), str(folder / "floor.o"), "-o", str(binary), "-lm"], check=True)
    return binary


def run(binary: Path, case: int, calls: int, rounds: int) -> dict:
    """One case of the program: its JSON object."""
    out = subprocess.run([str(binary), str(case), str(calls), str(rounds)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--calls", type=int, default=2000, help="calls per timed round (default 2000)")
    parser.add_argument("--rounds", type=int, default=21, help="rounds of each, alternating, median kept (default 21)")
    parser.add_argument("--export-from", type=Path, default=None, help="a checkout whose skysh writes the export")
    args = parser.parse_args()
    print(json.dumps(environment(calls=args.calls, rounds=args.rounds, export_from=str(args.export_from),
                                 loadavg=os.getloadavg())))
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        headers = {bands: header(bands, None) for bands in GROWTH_BANDS}
        exports = headers if args.export_from is None else {b: header(b, args.export_from) for b in GROWTH_BANDS}
        for level, flags in LEVELS.items():
            for bands in BANDS:
                binary = build(directory / f"{level}-{bands}", exports[bands], headers[bands], flags)
                for label, case in CASES.items():
                    got = run(binary, case, args.calls, args.rounds)
                    ratio = got["export_ns"] / got["floor_ns"] if got["floor_ns"] > 0 else None
                    print(json.dumps({"bench": label, "bands": bands, "level": level, "export_ns": got["export_ns"],
                                      "floor_ns": got["floor_ns"] or None,
                                      "ratio": None if ratio is None else round(ratio, 3),
                                      "max_diff_over_dc": got["max_diff_over_dc"]}), flush=True)
            for bands in GROWTH_BANDS:
                binary = build(directory / f"{level}-growth-{bands}", exports[bands], headers[bands], flags)
                got = run(binary, CASES["radiance"], args.calls, args.rounds)
                print(json.dumps({"bench": "growth", "bands": bands, "level": level, "export_ns": got["export_ns"],
                                  "floor_ns": got["floor_ns"], "table_entries": table_entries(bands),
                                  "ns_per_entry": round(got["export_ns"] / table_entries(bands), 4)}), flush=True)
    print(json.dumps({"bench": "loadavg_after", "loadavg": os.getloadavg()}))


def table_entries(bands: int) -> int:
    """The entries of SKYSH_TABLE at ``bands`` bands: terms x 3 x rows (one band: the c_10 row too)."""
    table = export_tables(SkySH.load(), bands).table
    return int(table.shape[0] * table.shape[1] * 3 * (table.shape[2] + (bands == 1)))


if __name__ == "__main__":
    main()
