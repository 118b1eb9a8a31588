"""
Per-call cost of the JavaScript module against a hand-written JavaScript floor
==============================================================================

The module (:func:`skysh.export.js.module_source`) and ``benchmarks/js_floor.mjs``'s floor
(the least JavaScript doing the same arithmetic for one fixed set of options, reading the
module's own data object) evaluate the same random frames in ONE node process, in turns
(module, floor, module, ... over ``--rounds`` rounds after a warm-up), and the median ns
per call of each is kept: a change in the machine's load hits both alike. The module is
timed with ``out`` (no allocation per call: the per-frame use the module documents) and,
as ``module_new_array_ns_per_call``, without it.

Cases (``radiance``: Gibbs on; ``irradiance``: deringing off; ``irradiance-default``: the
defaults, at 3 bands the certified irradiance table, at 7 the deringing, which the floor
does not do: its ratio is the deringing's cost; ``lit``: irradiance, deringing off, the
sun and a ground of albedo 0.2; ``lit-default-3``: the same with the defaults, the table),
each at 3 and 7 bands. Every line also gives the floor's agreement with the module (worst
|floor - module| over |DC| of the same channel, ``floor_max_diff_over_dc``): the floor
does the module's arithmetic, so its figure is rounding (about 1e-16).

Prints the environment first (with the 1-minute load average: on a loaded machine run it
a few times), then one JSON line per case; always exits 0 (the issue's target, the
module within 1.3x of the floor, is read off the ``ratio`` column, not enforced).

Run: ``PYTHONPATH=. python benchmarks/bench_js_floor.py [--calls 4000] [--rounds 15] [--only CASE ...]
[--module OLD.mjs]`` (``--module``: time that module file, e.g. one an older checkout exported, against the
same floor).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from _timing import environment

from skysh import SkySH
from skysh.export.js import module_data, module_source

FLOOR: Path = Path(__file__).with_name("js_floor.mjs")
"""The floor and the interleaved timing (node)."""

ALBEDO: float = 0.2
"""The lit cases' ground albedo (grey)."""


def cases() -> list[dict[str, Any]]:
    """Every case: its name, the module's options and the floor's fixed settings."""
    out = []
    for n in (3, 7):
        plain = {"bands": n, "gibbs": False, "irradiance": True, "table": False, "sun": False, "albedo": 0.0}
        table = n == 3  # the defaults by intent: the certified table at 3 bands, deringing at the others
        out += [
            {"name": f"radiance-{n}", "options": {"bands": n},
             "floor": {**plain, "gibbs": True, "irradiance": False}},
            {"name": f"irradiance-{n}", "options": {"bands": n, "irradiance": True, "dering": False}, "floor": plain},
            {"name": f"irradiance-default-{n}", "options": {"bands": n, "irradiance": True},
             "floor": {**plain, "table": table}},
            {"name": f"lit-{n}", "floor": {**plain, "sun": True, "albedo": ALBEDO},
             "options": {"bands": n, "irradiance": True, "dering": False, "sun": True, "groundAlbedo": ALBEDO}},
        ]
    out.append({"name": "lit-default-3", "options": {"bands": 3, "irradiance": True, "sun": True, "groundAlbedo": ALBEDO},
                "floor": {"bands": 3, "gibbs": False, "irradiance": True, "table": True, "sun": True, "albedo": ALBEDO}})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--calls", type=int, default=4000, help="frames per timed round (default 4000)")
    parser.add_argument("--rounds", type=int, default=15, help="timed rounds of each, in turns; medians (default 15)")
    parser.add_argument("--module", type=Path, default=None,
                        help="time this module file instead of a fresh export (e.g. one written by an older checkout)")
    parser.add_argument("--only", nargs="*", default=None, help="the cases to run, by name (default all)")
    args = parser.parse_args()
    node = shutil.which("node")
    if node is None:
        raise SystemExit("node is not installed")
    sky = SkySH.load()
    version = subprocess.run([node, "--version"], capture_output=True, check=True, text=True).stdout.strip()
    print(json.dumps(environment(node=version, calls=args.calls, rounds=args.rounds)), flush=True)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        module = args.module if args.module is not None else folder / "sky_sh.mjs"
        if args.module is None:
            module.write_text(module_source(sky))
        (folder / "data.json").write_text(module_data(sky))
        (folder / "cases.json").write_text(json.dumps([c for c in cases() if args.only is None or c["name"] in args.only]))
        subprocess.run([node, str(FLOOR), str(module.resolve()), str(folder / "data.json"),
                        str(folder / "cases.json"), str(args.calls), str(args.rounds)], check=True)


if __name__ == "__main__":
    main()
