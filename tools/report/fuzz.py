"""
Section 8 (e): fuzzing ``SkySH.coefficients``
=============================================

Random and adversarial calls in nine categories, then the count of every bad-input
kind the test suite feeds every public function and CLI command
(``tests/test_input_hygiene.py``) and every corrupted coefficient file
(``tests/table/test_corrupt_file.py``), run here and tallied from pytest's JUnit XML. The expected outcome is a finite
result for a valid call and a ValueError otherwise; a TypeError is recorded (and
counted as unexpected). Any other exception is not caught: it stops the report with
its traceback, since it is a bug of the runtime that no table should hide.
"""

from __future__ import annotations

import math
import subprocess
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from report.common import MAX_BANDS, Context, Section, sig
from skysh.domain import SKY

FUZZ_SEED: int = 99
"""Seed of the fuzzer's generator."""
HALF_PI: float = math.pi / 2.0
ZENITH_RANGE: tuple[float, float] = SKY.x.interval
TURBIDITY_RANGE: tuple[float, float] = SKY.y.interval
AZIMUTH_RANGE: tuple[float, float] = (-10.0, 10.0)
"""In-domain azimuths drawn (rad); any finite azimuth is valid."""
JUST_OUTSIDE_Z: tuple[float, ...] = (float(np.nextafter(0.0, -1.0)), float(np.nextafter(HALF_PI, 4.0)), -1e-300,
                                     HALF_PI + 1e-12, 3.2, -5.0, 1e300)
JUST_OUTSIDE_T: tuple[float, ...] = (float(np.nextafter(2.5, 0.0)), float(np.nextafter(6.0, 7.0)), 0.0, -1.0, 1.7, 10.0,
                                     1e300)
EDGE_Z: tuple[float, ...] = (0.0, -0.0, HALF_PI, float(np.nextafter(HALF_PI, 0.0)), float(np.nextafter(0.0, 1.0)))
EDGE_T: tuple[float, ...] = (2.5, 6.0, float(np.nextafter(2.5, 3.0)), float(np.nextafter(6.0, 5.0)))
HUGE_AZIMUTHS: tuple[float, ...] = (1e17, -1e17, 1e300, 1e308, -1.7e308, 2.0**1000, float(np.finfo(np.float64).max))
WEIRD: tuple[Any, ...] = (None, "0.5", complex(0.5, 0.0), [0.5], (0.5,), np.float32(0.5), np.float16(0.5), np.int64(0),
                          True, np.array(0.5), object(), b"1", {"a": 1})
ODD_BANDS: tuple[Any, ...] = (0, -1, 8, 100, 3.0, True, None, "3", np.int64(3), np.int32(7), 2**64, 7.5)
SPACES: tuple[Any, ...] = ("sRGB", "ITU-R BT.2020", "ACEScg", "srgb", "", None, 5, "not a colourspace")
OUTCOMES: tuple[str, ...] = ("finite", "nan_inf", "ValueError", "TypeError")
EXAMPLES_PER_CATEGORY: int = 3
TEXTUAL: tuple[type, ...] = (str, bytes, bool, np.bool_)
"""Values that are not angles or turbidities even where numpy would convert them."""
INTEGER_BANDS: tuple[type, ...] = (int, np.int64, np.int32)


@dataclass
class Case:
    """One call: ``coefficients(z, t, a, **kwargs)``."""

    z: Any
    t: Any
    a: Any
    kwargs: dict[str, Any] = field(default_factory=dict)

    def text(self) -> str:
        return f"coefficients({self.z!r}, {self.t!r}, {self.a!r}, {self.kwargs})"


def _pick(rng: np.random.Generator, values: tuple[Any, ...]) -> Any:
    return values[int(rng.integers(len(values)))]


def _replace_one(case: Case, value: Any, which: int) -> None:
    case.z, case.t, case.a = [value if k == which else v for k, v in enumerate((case.z, case.t, case.a))]


def _edges(case: Case, rng: np.random.Generator) -> None:
    case.z, case.t = float(rng.choice(EDGE_Z)), float(rng.choice(EDGE_T))


def _just_outside(case: Case, rng: np.random.Generator) -> None:
    if rng.integers(2):
        case.z = float(rng.choice(JUST_OUTSIDE_Z))
    else:
        case.t = float(rng.choice(JUST_OUTSIDE_T))


def _non_finite(case: Case, rng: np.random.Generator) -> None:
    bad = float(rng.choice([math.nan, math.inf, -math.inf]))
    _replace_one(case, bad, int(rng.integers(3)))


def _huge_azimuth(case: Case, rng: np.random.Generator) -> None:
    case.a = float(rng.choice(HUGE_AZIMUTHS))


def _arrays(case: Case, rng: np.random.Generator) -> None:
    n = int(rng.integers(0, 5))
    case.z = rng.uniform(*ZENITH_RANGE, n)
    case.t = rng.uniform(*TURBIDITY_RANGE, n) if rng.integers(2) else float(rng.uniform(*TURBIDITY_RANGE))
    case.a = rng.uniform(-4.0, 4.0, (1, n)) if rng.integers(2) else rng.uniform(-4.0, 4.0, n)
    if n and rng.integers(4) == 0:
        case.z[int(rng.integers(n))] = float(rng.choice([math.nan, -0.1, 2.0]))
    if rng.integers(6) == 0:
        case.t = rng.uniform(*TURBIDITY_RANGE, n + 1)  # shapes that do not broadcast


def _other_types(case: Case, rng: np.random.Generator) -> None:
    value = _pick(rng, WEIRD)
    _replace_one(case, value, int(rng.integers(3)))


def _bands(case: Case, rng: np.random.Generator) -> None:
    case.kwargs["bands"] = _pick(rng, ODD_BANDS)


def _flags(case: Case, rng: np.random.Generator) -> None:
    case.kwargs["colourspace"] = _pick(rng, SPACES)
    case.kwargs["dering"] = bool(rng.integers(8) == 0)
    if case.kwargs["dering"]:
        case.kwargs["bands"] = int(rng.integers(1, 4))


CATEGORIES: dict[str, Callable[[Case, np.random.Generator], None] | None] = {
    "in domain": None, "domain edges": _edges, "just outside": _just_outside, "non-finite": _non_finite,
    "huge azimuth": _huge_azimuth, "arrays": _arrays, "other types": _other_types, "bands": _bands,
    "flags and colourspace": _flags,
}
"""The categories in turn, each with how it changes a valid call (None: it stays valid)."""


def make_case(category: str, rng: np.random.Generator) -> Case:
    """A valid call, then changed as ``category`` says."""
    case = Case(float(rng.uniform(*ZENITH_RANGE)), float(rng.uniform(*TURBIDITY_RANGE)), float(rng.uniform(*AZIMUTH_RANGE)))
    case.kwargs = {"bands": int(rng.integers(1, MAX_BANDS + 1)), "gibbs": bool(rng.integers(2)),
                   "irradiance": bool(rng.integers(2))}
    change = CATEGORIES[category]
    if change is not None:
        change(case, rng)
    return case


def _as_numbers(case: Case) -> tuple[np.ndarray, ...] | None:
    """The sun's parameters as float arrays that broadcast together, or None (text, not numbers, bad shapes)."""
    if any(isinstance(v, TEXTUAL) for v in (case.z, case.t, case.a)):
        return None
    try:
        values = tuple(np.asarray(v, dtype=np.float64) for v in (case.z, case.t, case.a))
        np.broadcast_shapes(*(v.shape for v in values))
    except (TypeError, ValueError):  # not numbers, or shapes that do not broadcast: the call must refuse
        return None
    return values


def _within(values: np.ndarray, bounds: tuple[float, float]) -> bool:
    return values.size == 0 or bool(values.min() >= bounds[0] and values.max() <= bounds[1])


def _valid_sun(case: Case) -> bool:
    """The sun's parameters are numbers that broadcast, are finite and lie in the domain."""
    values = _as_numbers(case)
    if values is None or not all(np.all(np.isfinite(v)) for v in values):
        return False
    return _within(values[0], ZENITH_RANGE) and _within(values[1], TURBIDITY_RANGE)


@cache
def _colourspaces() -> Any:
    """colour-science's colourspaces (a dependency; imported on first use, it takes seconds)."""
    import colour

    return colour.RGB_COLOURSPACES


def expected_outcome(case: Case) -> str:
    """"finite" for a valid call, else "ValueError"."""
    bands, space = case.kwargs["bands"], case.kwargs.get("colourspace")
    valid_bands = type(bands) in INTEGER_BANDS and 1 <= int(bands) <= MAX_BANDS
    valid_space = space is None or (isinstance(space, str) and space in _colourspaces())  # case-insensitive names
    return "finite" if _valid_sun(case) and valid_bands and valid_space else "ValueError"


def run_case(sky: Any, case: Case) -> tuple[str, int]:
    """The outcome of one call and the RuntimeWarnings it raised (other exceptions propagate)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = sky.coefficients(case.z, case.t, case.a, **case.kwargs)
            outcome = "finite" if bool(np.all(np.isfinite(out))) else "nan_inf"
        except ValueError:
            outcome = "ValueError"
        except TypeError:
            outcome = "TypeError"
    return outcome, sum(1 for w in caught if issubclass(w.category, RuntimeWarning))


def _tally(stats: dict[str, int], examples: list[str], category: str, case: Case, outcome: str) -> None:
    """Count one call's outcome; an unexpected one is counted as such and kept as an example (a few per category)."""
    expected = expected_outcome(case)
    stats["tried"] += 1
    stats[outcome] += 1
    if outcome == expected:
        return
    stats["unexpected"] += 1
    stats["lenient"] += int(outcome == "finite" and any(isinstance(v, TEXTUAL) for v in (case.z, case.t, case.a)))
    if len(examples) < EXAMPLES_PER_CATEGORY:
        examples.append(f"{category}: {case.text()} gave {outcome}, expected {expected}")


def compute(ctx: Context) -> dict[str, Any]:
    """Outcomes by category, up to three unexpected examples per category, and the numpy RuntimeWarnings."""
    rng = np.random.default_rng(FUZZ_SEED)
    names = list(CATEGORIES)
    stats = {c: {"tried": 0, **{o: 0 for o in OUTCOMES}, "lenient": 0, "unexpected": 0} for c in names}
    examples: dict[str, list[str]] = {c: [] for c in names}
    warning_count = 0
    start = time.perf_counter()
    with ctx.bar(ctx.plan.fuzz_inputs, "8e. fuzzing") as bar:
        for i in range(ctx.plan.fuzz_inputs):
            category = names[i % len(names)]
            case = make_case(category, rng)
            outcome, count = run_case(ctx.sky, case)
            warning_count += count
            _tally(stats[category], examples[category], category, case, outcome)
            bar.update(1)
    return {"stats": stats, "examples": [e for v in examples.values() for e in v], "runtime_warnings": warning_count,
            "seconds": time.perf_counter() - start, "suites": suite_counts(Path(__file__).resolve().parents[2])}


SUITES: dict[str, str] = {
    "bad values, every public function and CLI command": "tests/test_input_hygiene.py",
    "corrupted coefficient files": "tests/table/test_corrupt_file.py",
}
"""The test files whose cases the report counts (one row each)."""


def suite_counts(root: Path) -> dict[str, dict[str, int]]:
    """Run each file of :data:`SUITES` with pytest and count its cases: passed, failed, skipped, expected failures."""
    counts = {}
    for label, path in SUITES.items():
        with tempfile.TemporaryDirectory() as tmp:
            xml_path = Path(tmp) / "junit.xml"
            subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", path,
                            f"--junitxml={xml_path}"], cwd=root, capture_output=True, check=False, timeout=900)
            cases = ET.parse(xml_path).getroot().iter("testcase")
            tally = {"cases": 0, "passed": 0, "failed": 0, "skipped": 0}
            for case in cases:
                tally["cases"] += 1
                kinds = {child.tag for child in case}
                key = "failed" if kinds & {"failure", "error"} else "skipped" if "skipped" in kinds else "passed"
                tally[key] += 1
            counts[label] = tally
    return counts


def _nan_text(examples: list[str]) -> str | None:
    """Where NaN or inf came from, if any call gave them."""
    nan_cases = [e for e in examples if "nan_inf" in e]
    if not nan_cases:
        return None
    if all(e.startswith("huge azimuth") for e in nan_cases):
        return ("NaN or inf came only from huge finite azimuths: the runtime multiplies the azimuth by m before "
                "taking cos and sin, which overflows to inf for |sun_azimuth| above about 1.8e308 / (N - 1); "
                "`sun_azimuth` is documented as 'any finite value'.")
    return "NaN or inf came from the calls listed above."


def render(ctx: Context, s: Section, d: dict[str, Any]) -> None:
    """The fuzzing sub-section of section 8."""
    stats = d["stats"]
    s.text(f"**Fuzzing `SkySH.coefficients`**: {ctx.plan.fuzz_inputs} calls in {sig(d['seconds'])} s, random and "
           f"adversarial inputs in {len(stats)} categories; 'expected' is a finite result for an in-domain call and a "
           "ValueError otherwise; 'unexpected' counts calls that did anything else (NaN/inf, a TypeError, a refusal "
           "of a valid call or silent extrapolation). Any other exception would have stopped this report. "
           f"RuntimeWarnings raised by numpy during the calls: {d['runtime_warnings']}.")
    columns = ("tried", "finite", "nan_inf", "ValueError", "TypeError", "lenient", "unexpected")
    s.table(["category", "tried", "finite result", "NaN or inf", "ValueError", "TypeError",
             "text or bool taken as a number", "unexpected (all kinds)"],
            [[c] + [v[k] for k in columns] for c, v in stats.items()])
    if d["examples"]:
        s.text(f"Unexpected outcomes (at most {EXAMPLES_PER_CATEGORY} per category):")
        s.raw([f"- `{e}`" for e in d["examples"]])
    total = {k: sum(v[k] for v in stats.values()) for k in ("tried", "nan_inf", "TypeError", "lenient")}
    ctx.note("Fuzzing SkySH.coefficients: inputs tried / NaN-inf results / TypeErrors / text or bool accepted as "
             "numbers", f"{total['tried']} / {total['nan_inf']} / {total['TypeError']} / {total['lenient']}", "")
    nan_text = _nan_text(d["examples"])
    if nan_text is not None:
        s.text(nan_text)
    suites = d["suites"]
    s.text("**Every kind of bad input, every public function**: the test suite's table-driven cases (each asserts the "
           "exception type and that the message names the parameter or CLI flag) and its corrupted-file cases (each "
           "asserts one CoefficientFileError within 64 MB), run for this report:")
    s.table(["suite", "cases", "passed", "failed", "skipped (expected failures included)"],
            [[label, v["cases"], v["passed"], v["failed"], v["skipped"]] for label, v in suites.items()])
    ctx.note("Bad-input cases (every public function and CLI flag) / corrupted files: passed of run",
             " / ".join(f"{v['passed']} of {v['cases']}" for v in suites.values()), "")
