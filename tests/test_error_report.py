"""
Tests of the error report (``tools/error_report.py`` and ``tools/report/``)
==========================================================================

The quick report is built in a subprocess exactly as a user runs it
(``python tools/error_report.py --out DIR --quick --sections ...``) and checked:
it exits cleanly, report.md has the summary table and every requested section in
order, every chart it references exists, every PNG in the directory is referenced
and is a valid PNG (parsed here chunk by chunk, CRCs checked and the image data
inflated, independently of matplotlib), and the charts are small. The default run
takes the fewest sections that still pass through every shared module (section 9:
the process pool, the memoised grids and sweep, the studies; section 10: the
renders); the run of every section is marked ``slow``.

Without cvxpy (the tools extra) the report skips section 11, says so in report.md and completes: a quick run of
sections 6 and 11 in an interpreter where cvxpy cannot be imported, whether or not it is installed. The tests that
solve are skipped without it (``conftest.needs_cvxpy``).

Sections 11 and 12 also run in process at the quick sizes: their tables and charts, the tabulated
irradiance within issue 18's bound and never negative (gibbs=True and a scaled projection must exceed it), the
lune quadrature against closed forms and against the 64-band projection (a wrong sun azimuth must miss), the
ground exact (a wrong albedo must miss).

In-process: the section registry, the loud failure of a section that raises (no
"not measured"), the absence of catch-all handlers and of other modules' private
names in the report's source, and the report's helpers against independent routes.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import math
import os
import re
import struct
import subprocess
import sys
import time
import types
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, fibonacci_sphere, needs_cvxpy, script_without_cvxpy

pytestmark = [pytest.mark.xdist_group("error_report")] if importlib.util.find_spec("xdist") else []
"""``pytest -n N --dist loadgroup``: one worker runs this module (its module fixtures once; the quick run is shared)."""

TOOL = ROOT / "tools" / "error_report.py"
PACKAGE = ROOT / "tools" / "report"

TIMEOUT_S: float = 600.0
"""Hang guard: a quick run killed after this fails with a clear message (its speed is measured by the
run itself, printed in its summary, not asserted here)."""

WIRING_SECTIONS: tuple[int, ...] = (9, 10)
"""The default run's sections: 9 goes through report.data (process pool, memo), report.studies and
report.common; 10 through the renders. Two, so that the order and the joining of sections are checked."""

MIN_SUMMARY_ROWS: dict[str, int] = {"wiring": 2, "all": 13}
"""The summary gathers at least this many key numbers: section 9's and the run time; one or more per
section in the run of every section."""

PNG_TOTAL_BYTES_MAX: int = 3_500_000
"""The bound on the committed report's PNGs (the quick charts are smaller): 3.3 MB for 13 sections, of which section
13's four charts (the two skies side by side at three suns, the rule's accuracy-cost curve) are 0.72 MB."""

EXACT: float = 1e-12
"""Relative tolerance where the report's helper and the independent route compute the same sums."""

SOLVE: float = 1e-9
"""Relative tolerance between the SVD least squares and the normal equations on a well-conditioned
problem (condition number about 10, so the normal equations lose about 2 of 16 digits)."""

PNG_SIGNATURE: bytes = b"\x89PNG\r\n\x1a\n"
"""The 8 bytes every PNG starts with (PNG specification, section 5.2)."""

PNG_CHANNELS: dict[int, int] = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
"""Samples per pixel of each PNG colour type (grey, RGB, palette, grey + alpha, RGBA)."""

RUNS: dict[str, tuple[int, ...] | None] = {"wiring": WIRING_SECTIONS, "all": None}
"""The quick runs: the default one and every section (None: no --sections)."""

SKIPPED: str = "**Skipped in this run**"
"""How report.md opens a section skipped for a missing package of the tools extra."""

SOLVER_SECTION: int = 11
"""The section that solves convex problems (cvxpy): skipped without the tools extra."""

CHEAP_SECTION: int = 6
"""A section that needs no optional package and takes about a second at the quick sizes (the quantization table)."""


def load_tool() -> types.ModuleType:
    """Import tools/error_report.py as ``skysh report`` does (tools/ is not a package); it puts tools/ on the path."""
    spec = importlib.util.spec_from_file_location("error_report", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def tool() -> types.ModuleType:
    return load_tool()


@pytest.fixture(scope="module")
def report(tool: types.ModuleType) -> types.SimpleNamespace:
    """The report's modules, imported after the tool put tools/ on the path."""
    names = ("run", "common", "plans", "fuzz", "studies", "s05_dering", "s08_stability", "s10_pictures",
             "s11_irradiance_table", "s12_scene_irradiance", "s13_hosek")
    return types.SimpleNamespace(**{n: importlib.import_module(f"report.{n}") for n in names})


def quick_command(name: str, out: Path) -> list[str]:
    """The command line of the quick run ``name`` (RUNS) writing to ``out``, as a user runs it."""
    command = [sys.executable, str(TOOL), "--out", str(out), "--quick", "--no-progress"]
    sections = RUNS[name]
    return command if sections is None else [*command, "--sections", ",".join(map(str, sections))]


def quick_env() -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))


def in_xdist_worker(config: pytest.Config) -> bool:
    """True in a pytest-xdist worker process (which collects every test but runs only those it is sent)."""
    return hasattr(config, "workerinput")


@pytest.fixture(scope="module")
def wiring_run(request: pytest.FixtureRequest,
               tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[subprocess.Popen | None, Path]]:
    """The default quick run, once per session, in the background: (its process, or None where another pytest-xdist
    worker started it; its folder: report in ``out/``, output in ``stdout``, ``stderr``). Under xdist the folder is in
    the temporary folder all workers share; the first to ask creates ``started`` exclusively and starts the run.
    A run left unread is killed with the module's teardown."""
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if in_xdist_worker(request.config) else base) / "report_wiring"
    folder.mkdir(exist_ok=True)
    try:
        os.close(os.open(folder / "started", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        yield None, folder
        return
    with open(folder / "stdout", "w", encoding="utf-8") as stdout, open(folder / "stderr", "w", encoding="utf-8") as stderr:
        process = subprocess.Popen(quick_command("wiring", folder / "out"), cwd=ROOT, env=quick_env(), stdout=stdout,
                                   stderr=stderr, text=True)
    yield process, folder
    if process.poll() is None:
        process.kill()
        process.wait()


def wiring_result(process: subprocess.Popen | None, folder: Path) -> subprocess.CompletedProcess:
    """The finished default quick run: its starter waits and writes ``returncode`` atomically, others wait for it."""
    status = folder / "returncode"
    if process is not None:
        try:
            process.wait(timeout=TIMEOUT_S)
            code = str(process.returncode)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            code = "timeout"
        (folder / "returncode.part").write_text(code, encoding="utf-8")
        os.replace(folder / "returncode.part", status)
    deadline = time.monotonic() + TIMEOUT_S
    while not status.exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    code = status.read_text(encoding="utf-8") if status.exists() else "timeout"
    if code == "timeout":
        pytest.fail(f"{' '.join(quick_command('wiring', folder / 'out')[1:])} did not finish within {TIMEOUT_S:.0f} s")
    return subprocess.CompletedProcess(quick_command("wiring", folder / "out"), int(code),
                                       (folder / "stdout").read_text(encoding="utf-8"),
                                       (folder / "stderr").read_text(encoding="utf-8"))


@pytest.fixture(scope="module", autouse=True)
def _start_the_wiring_run(request: pytest.FixtureRequest) -> None:
    """Start the default quick run with the module's first test when a selected test reads it: the run then
    works in its own process while the in-process tests below run, and TestQuickRun (marked ``late``:
    conftest runs it after the rest of the module) waits for it.

    Not in a pytest-xdist worker, which cannot know whether it will be sent TestQuickRun: there :func:`quick` starts
    the run when first asked (one run for all workers: :func:`wiring_run`)."""
    if not in_xdist_worker(request.config) and any(
            item.module is request.module and "quick" in item.fixturenames and "[wiring]" in item.nodeid
            for item in request.session.items):
        request.getfixturevalue("wiring_run")


@pytest.fixture(scope="module", params=[pytest.param("wiring"), pytest.param("all", marks=pytest.mark.slow)])
def quick(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> dict:
    name = request.param
    if name == "wiring":
        process, folder = request.getfixturevalue("wiring_run")
        proc, out = wiring_result(process, folder), folder / "out"
    else:
        out = tmp_path_factory.mktemp(f"report_{name}")
        command = quick_command(name, out)
        try:
            proc = subprocess.run(command, cwd=ROOT, env=quick_env(), capture_output=True, text=True, timeout=TIMEOUT_S,
                                  check=False)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{' '.join(command[1:])} did not finish within {TIMEOUT_S:.0f} s")
    report_md = out / "report.md"
    return {"name": name, "sections": RUNS[name], "out": out, "proc": proc,
            "text": report_md.read_text(encoding="utf-8") if report_md.exists() else ""}


def png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    """(type, payload) of every chunk, checking the signature, lengths and CRC-32s."""
    assert data[:8] == PNG_SIGNATURE, "not a PNG signature"
    chunks, pos = [], 8
    while pos < len(data):
        assert pos + 12 <= len(data), "truncated chunk header"
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        payload = data[pos + 8 : pos + 8 + length]
        assert len(payload) == length, f"truncated {kind!r} chunk"
        (crc,) = struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])
        assert crc == zlib.crc32(kind + payload) & 0xFFFFFFFF, f"bad CRC in {kind!r}"
        chunks.append((kind, payload))
        pos += 12 + length
    return chunks


def check_png(path: Path) -> tuple[int, int]:
    """Parse a PNG fully (IHDR, inflated IDAT of the right size with valid row filters, IEND last); return (width, height)."""
    chunks = png_chunks(path.read_bytes())
    kinds = [k for k, _ in chunks]
    assert kinds[0] == b"IHDR" and kinds[-1] == b"IEND" and b"IDAT" in kinds
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunks[0][1])
    assert width > 0 and height > 0 and depth in (1, 2, 4, 8, 16) and colour in PNG_CHANNELS
    raw = zlib.decompress(b"".join(p for k, p in chunks if k == b"IDAT"))
    if interlace == 0:
        stride = 1 + math.ceil(width * PNG_CHANNELS[colour] * depth / 8)
        assert len(raw) == height * stride, "image data of the wrong size"
        assert set(raw[::stride]) <= {0, 1, 2, 3, 4}, "invalid row filter"
    return width, height


def section_spans(text: str, titles: dict[int, str]) -> list[tuple[int, int, int]]:
    """(number, start, end) of every section heading in the text, in the text's order."""
    found = sorted((text.index(f"\n## {k}. {t}\n"), k) for k, t in titles.items() if f"\n## {k}. {t}\n" in text)
    ends = [start for start, _ in found[1:]] + [len(text)]
    return [(k, start, end) for (start, k), end in zip(found, ends)]


# --------------------------------------------------------------------------- #
@pytest.mark.late  # reads the quick run started in the background when the module began
class TestQuickRun:
    def test_exits_cleanly(self, quick: dict) -> None:
        proc = quick["proc"]
        assert proc.returncode == 0, f"exit {proc.returncode}\nstdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-4000:]}"
        assert "wrote" in proc.stdout

    def test_requested_sections_present_in_order(self, quick: dict, report: types.SimpleNamespace) -> None:
        titles = report.run.SECTION_TITLES
        wanted = list(titles) if quick["sections"] is None else list(quick["sections"])
        spans = section_spans(quick["text"], titles)
        assert [k for k, _, _ in spans] == wanted, f"sections {[k for k, _, _ in spans]}, wanted {wanted}"

    def test_no_section_failed(self, quick: dict) -> None:
        assert "Traceback" not in quick["text"]
        assert "not measured" not in quick["text"]

    def test_summary_table_at_the_top(self, quick: dict) -> None:
        text = quick["text"]
        first = text.index("\n## ", text.index("## Summary") + 1)
        assert text.index("## Summary") < first
        summary = text[text.index("## Summary") : first]
        rows = [line for line in summary.splitlines() if line.startswith("| ") and not line.startswith("| quantity")]
        assert len(rows) >= MIN_SUMMARY_ROWS[quick["name"]]
        for row in rows:
            cells = [c.strip() for c in row.strip("|").split("|")]
            assert cells[1], f"empty value in summary row {row!r}"
            assert not re.search(r"\bnan\b", cells[1], re.IGNORECASE), f"NaN in summary row {row!r}"

    def test_every_section_has_a_chart(self, quick: dict, report: types.SimpleNamespace) -> None:
        text = quick["text"]
        skipped = {k for k in report.run.SECTIONS if report.run.missing_packages(k)}  # those without the tools extra
        for number, start, end in section_spans(text, report.run.SECTION_TITLES):
            if number in skipped:
                assert SKIPPED in text[start:end], f"section {number} lacks a package but was not skipped"
                continue
            assert SKIPPED not in text[start:end], f"section {number} skipped"
            assert re.search(r"!\[[^\]]+\]\([^)]+\.png\)", text[start:end]), f"section {number} has no chart"

    def test_referenced_charts_exist_and_all_are_referenced(self, quick: dict) -> None:
        out: Path = quick["out"]
        referenced = re.findall(r"!\[[^\]]+\]\(([^)]+)\)", quick["text"])
        assert referenced, "no charts referenced"
        for name in referenced:
            assert (out / name).is_file(), f"report.md references missing {name}"
        on_disk = {p.name for p in out.glob("*.png")}
        assert on_disk == set(referenced), f"unreferenced PNGs: {sorted(on_disk - set(referenced))}"

    def test_pngs_are_valid(self, quick: dict) -> None:
        pngs = sorted(quick["out"].glob("*.png"))
        assert pngs
        for path in pngs:
            width, height = check_png(path)
            assert 200 <= width <= 3000 and 100 <= height <= 3000, f"{path.name}: odd size {width} x {height}"

    def test_pngs_decode_with_matplotlib(self, quick: dict) -> None:
        import matplotlib.image

        for path in sorted(quick["out"].glob("*.png")):
            image = matplotlib.image.imread(path)
            assert image.ndim == 3 and image.shape[2] in (3, 4)
            assert np.ptp(image[..., :3]) > 0, f"{path.name} is blank"

    def test_charts_are_small(self, quick: dict) -> None:
        total = sum(p.stat().st_size for p in quick["out"].glob("*.png"))
        assert total < PNG_TOTAL_BYTES_MAX

    def test_numbers_come_from_the_run(self, quick: dict) -> None:
        # The header names the run; the summary's run time is this run's: positive and finite.
        text = quick["text"]
        assert "(quick run)" in text
        match = re.search(r"\| Report run time \(this run\) \| ([0-9.e+]+) s", text)
        assert match and 0.0 < float(match.group(1)) < math.inf


# --------------------------------------------------------------------------- #
class TestWiring:
    def test_every_section_module_is_registered(self, report: types.SimpleNamespace) -> None:
        sections = report.run.SECTIONS
        assert list(sections) == list(range(1, 14))
        for number, module in sections.items():
            assert module.NUMBER == number and isinstance(module.TITLE, str) and module.TITLE
            assert callable(module.compute) and callable(module.render)
        assert report.run.SECTION_TITLES == {k: m.TITLE for k, m in sections.items()}

    def test_help_lists_every_section(self, tool: types.ModuleType, report: types.SimpleNamespace,
                                      capsys: pytest.CaptureFixture[str]) -> None:
        with pytest.raises(SystemExit) as info:
            tool.main(["--help"])
        assert info.value.code == 0
        out = capsys.readouterr().out
        for number, title in report.run.SECTION_TITLES.items():
            assert f"{number:2d}. {title}" in out

    @pytest.mark.parametrize("argv", [["--sections", "99"], ["--sections", "x"], ["--jobs", "0"]])
    def test_refuses_bad_arguments(self, tool: types.ModuleType, tmp_path: Path, argv: list[str]) -> None:
        with pytest.raises(SystemExit) as info:
            tool.main(["--out", str(tmp_path), *argv])
        assert info.value.code == 2

    @pytest.mark.parametrize("error", [AttributeError, TypeError])
    def test_a_failing_section_fails_the_run_loudly(self, tool: types.ModuleType, report: types.SimpleNamespace,
                                                    tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                    error: type[Exception]) -> None:
        def broken(ctx: object) -> dict:
            raise error("skysh.app.render has no attribute 'render_image'")

        monkeypatch.setattr(report.s10_pictures, "compute", broken)
        with pytest.raises(error, match="render_image"):
            tool.main(["--out", str(tmp_path), "--quick", "--sections", "10", "--no-progress"])
        assert not (tmp_path / "report.md").exists()  # no report that says "not measured"

    def test_no_catch_all_handlers(self) -> None:
        for path in [TOOL, *sorted(PACKAGE.glob("*.py"))]:
            text = path.read_text(encoding="utf-8")
            assert not re.search(r"except\s*(\(?\s*(Base)?Exception\b|:)", text), f"{path.name} has a catch-all handler"

    def test_no_private_names_of_other_modules(self) -> None:
        # the grep check: no `module._private` (nor `from x import _private`) in the report
        for path in [TOOL, *sorted(PACKAGE.glob("*.py"))]:
            text = path.read_text(encoding="utf-8")
            assert not re.findall(r"\b[a-z_]+\._[a-z]", text), f"{path.name} reaches into a private name"
            assert not re.findall(r"import\s+_[a-z]", text), f"{path.name} imports a private name"

    def test_studies_are_imported_in_one_place(self, report: types.SimpleNamespace) -> None:
        for path in sorted(PACKAGE.glob("*.py")):
            if path.name == "studies.py":
                continue
            text = path.read_text(encoding="utf-8")
            assert not re.search(r"^\s*(from|import) (studies|quantize_experiment)\b", text, re.MULTILINE), \
                f"{path.name} imports a study module directly instead of through report.studies"
            for name in report.studies.__all__:
                assert not re.search(rf"\b(hazel|quantize|quantize_experiment|hazel_study|quantize_study|sky)\.{name}\b", text), \
                    f"{path.name} uses {name} directly instead of through report.studies"


# --------------------------------------------------------------------------- #
class TestWithoutCvxpy:
    def test_the_report_skips_the_solver_section_and_completes(self, report: types.SimpleNamespace,
                                                               tmp_path: Path) -> None:
        sections = (CHEAP_SECTION, SOLVER_SECTION)
        command = script_without_cvxpy(TOOL, "--out", str(tmp_path), "--quick", "--no-progress", "--sections",
                                       ",".join(map(str, sections)))
        proc = subprocess.run(command, cwd=ROOT, env=quick_env(), capture_output=True, text=True, timeout=TIMEOUT_S,
                              check=False)
        assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-4000:]
        text = (tmp_path / "report.md").read_text(encoding="utf-8")
        spans = {k: text[start:end] for k, start, end in section_spans(text, report.run.SECTION_TITLES)}
        assert list(spans) == list(sections)
        skipped = spans[SOLVER_SECTION]
        assert skipped.strip().split("\n\n", 1)[1].startswith(SKIPPED)  # right under its heading
        assert "cvxpy" in skipped and "the `tools` extra" in skipped and '`pip install -e ".[tools]"`' in skipped
        assert not re.search(r"!\[[^\]]+\]\([^)]+\.png\)", skipped) and SKIPPED not in spans[CHEAP_SECTION]
        assert re.search(r"!\[[^\]]+\]\([^)]+\.png\)", spans[CHEAP_SECTION])  # the rest of the report ran
        title = report.run.SECTION_TITLES[SOLVER_SECTION]
        summary = text[text.index("## Summary") : text.index(f"\n## {CHEAP_SECTION}. ")]
        assert re.search(rf"^\| Section {SOLVER_SECTION}\. {re.escape(title)} \| skipped: needs cvxpy", summary, re.MULTILINE)
        assert f"[{SOLVER_SECTION}. {title}](#" in summary and "(skipped: needs cvxpy" in summary
        assert f"section {SOLVER_SECTION} ({title}) skipped: needs cvxpy" in proc.stderr
        assert 'pip install -e ".[tools]"' in proc.stderr and "skipped sections 11" in proc.stdout

    def test_a_skipped_section_computes_nothing(self, tool: types.ModuleType, report: types.SimpleNamespace,
                                                tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
        s11 = report.s11_irradiance_table

        def computed(ctx: object) -> dict:
            raise AssertionError("a section without its packages was computed")

        monkeypatch.setattr(s11, "missing_packages", lambda: ("cvxpy",))
        monkeypatch.setattr(s11, "compute", computed)
        assert tool.main(["--out", str(tmp_path), "--quick", "--sections", str(SOLVER_SECTION), "--no-progress"]) == 0
        assert SKIPPED in (tmp_path / "report.md").read_text(encoding="utf-8")

    def test_the_solver_section_asks_the_solver_helper(self, report: types.SimpleNamespace) -> None:
        from skysh.table import irradiance_fit

        assert report.s11_irradiance_table.missing_packages is irradiance_fit.missing_solver_packages
        assert report.run.missing_packages(SOLVER_SECTION) == irradiance_fit.missing_solver_packages()
        assert [k for k in report.run.SECTIONS if hasattr(report.run.SECTIONS[k], report.run.MISSING_PACKAGES)] \
            == [SOLVER_SECTION]  # the only section that imports cvxpy (through skysh.table.irradiance_fit)


# --------------------------------------------------------------------------- #
class TestHelpers:
    def test_error_all_is_eq3_over_every_coefficient(self, report: types.SimpleNamespace) -> None:
        rng = np.random.default_rng(1)
        truth = rng.normal(size=(5, 49, 3))
        predicted = truth + 1e-3 * rng.normal(size=truth.shape)
        denominator = rng.uniform(0.5, 2.0, (5, 3))
        for bands in (1, 2, 3, 6, 7):
            k = bands * bands
            direct = (np.sqrt(((predicted[:, :k] - truth[:, :k]) ** 2).sum(axis=1)) / denominator).max(axis=1)
            l1 = (np.abs(predicted[:, :k] - truth[:, :k]).sum(axis=1) / denominator).max(axis=1)
            got = report.common.error_all(predicted, truth, denominator, bands)
            np.testing.assert_allclose(got["e_mean"], direct, rtol=EXACT)
            np.testing.assert_allclose(got["e_max"], l1, rtol=EXACT)

    def test_full_from_half_places_the_m_nonnegative_rows(self, report: types.SimpleNamespace) -> None:
        from skysh.sh import basis as sh
        from skysh.table import coefficient_file

        half = np.arange(28 * 2, dtype=float).reshape(28, 2) + 1.0
        full = report.common.full_from_half(half, 7)
        for row, (degree, m) in enumerate(coefficient_file.zonal_half_layout(7)):
            np.testing.assert_array_equal(full[sh.index(degree, m)], half[row])
            if m:
                np.testing.assert_array_equal(full[sh.index(degree, -m)], 0.0)

    def test_gibbs_filter_matches_the_runtime(self, report: types.SimpleNamespace) -> None:
        from skysh import SkySH

        sky = SkySH.load()
        raw = sky.coefficients(0.6, 3.4, 0.0, bands=5, gibbs=False)
        np.testing.assert_allclose(report.common.gibbs_filter(raw), sky.coefficients(0.6, 3.4, 0.0, bands=5, gibbs=True),
                                   rtol=EXACT, atol=0.0)

    def test_pareto_front(self, report: types.SimpleNamespace) -> None:
        x = np.array([1.0, 2.0, 3.0, 1.5, 4.0])
        y = np.array([5.0, 3.0, 4.0, 6.0, 1.0])
        assert report.common.pareto(x, y).tolist() == [0, 1, 4]

    def test_cost_to_reach_power_law(self, report: types.SimpleNamespace) -> None:
        n = np.array([100.0, 400.0, 1600.0])
        error = 1.0 / np.sqrt(n)
        seconds = 1e-6 * n
        t, samples, extrapolated = report.common.cost_to_reach(seconds, error, n, 1.0 / math.sqrt(800.0))
        assert not extrapolated and samples == pytest.approx(800.0, rel=EXACT) and t == pytest.approx(8e-4, rel=EXACT)
        t, samples, extrapolated = report.common.cost_to_reach(seconds, error, n, 1.0 / math.sqrt(6400.0))
        assert extrapolated and samples == pytest.approx(6400.0, rel=EXACT)

    def test_interleaved_best_calls_each_function_round_by_round(self, report: types.SimpleNamespace) -> None:
        calls: list[str] = []
        functions = {name: (lambda name=name: calls.append(name)) for name in ("a", "b")}
        best = report.common.interleaved_best(functions, 3, 2)
        assert calls == ["a", "b"] + ["a", "a", "b", "b"] * 3  # warm-up, then rounds of 2 calls each
        assert set(best) == {"a", "b"} and all(0.0 <= v < math.inf for v in best.values())

    def test_weighted_lstsq_against_normal_equations(self, report: types.SimpleNamespace) -> None:
        rng = np.random.default_rng(3)
        design = rng.normal(size=(40, 5)) + 3.0 * np.eye(40, 5)
        values = rng.normal(size=(40, 2, 3))
        denominator = rng.uniform(0.5, 2.0, (40, 3))
        solution, condition = report.s08_stability.weighted_lstsq(design, values, denominator)
        for c in range(3):
            w2 = 1.0 / denominator[:, c] ** 2
            direct = np.linalg.solve(design.T @ (w2[:, None] * design), design.T @ (w2[:, None] * values[..., c]))
            np.testing.assert_allclose(solution[..., c], direct, rtol=SOLVE)
        weighted = [design / denominator[:, c, None] for c in range(3)]
        assert condition == pytest.approx(max(np.linalg.cond(a) for a in weighted), rel=SOLVE)

    @pytest.mark.parametrize(("change", "expected"), [
        ({}, "finite"),
        ({"z": math.pi / 2 + 1e-12}, "ValueError"),
        ({"t": 6.000001}, "ValueError"),
        ({"a": math.nan}, "ValueError"),
        ({"z": "0.5"}, "ValueError"),
        ({"z": True}, "ValueError"),
        ({"z": np.array([0.1, 0.2]), "t": np.array([3.0, 4.0, 5.0])}, "ValueError"),
        ({"z": np.array([0.1, 0.2]), "a": 1e300}, "finite"),
        ({"bands": 8}, "ValueError"),
        ({"bands": 3.0}, "ValueError"),
        ({"colourspace": "srgb"}, "finite"),
        ({"colourspace": "not a colourspace"}, "ValueError"),
    ])
    def test_fuzz_expectations(self, report: types.SimpleNamespace, change: dict, expected: str) -> None:
        fuzz = report.fuzz
        case = fuzz.Case(0.5, 3.0, 0.2, {"bands": 3, "gibbs": False, "irradiance": False})
        for key, value in change.items():
            if key in ("bands", "colourspace"):
                case.kwargs[key] = value
            else:
                setattr(case, key, value)
        assert fuzz.expected_outcome(case) == expected

    def test_every_fuzz_category_makes_a_case(self, report: types.SimpleNamespace) -> None:
        rng = np.random.default_rng(0)
        for category in report.fuzz.CATEGORIES:
            case = report.fuzz.make_case(category, rng)
            assert {"bands", "gibbs", "irradiance"} <= set(case.kwargs)
        valid = report.fuzz.make_case("in domain", rng)
        assert report.fuzz.expected_outcome(valid) == "finite"


# --------------------------------------------------------------------------- #
# Sections 11 and 12, in process at the quick sizes
# --------------------------------------------------------------------------- #
WINDOW_EXACT: float = 1e-15
"""The continuous window at the table's sizes against the table's rows: the same few operations in another order."""

LUNE_EXACT: float = 1e-12
"""The lune rule with unit radiance against pi (1 +- n_z) / 2: Gauss rules of 12 nodes per panel integrate the
integrands (sin^2 t, cos(psi - psi_n): entire functions of small degree on short panels) to rounding."""

BRUTE_VS_SH: float = 1e-4
"""Brute-force sky irradiance against the 64-band projection's, of the mean irradiance: the 64-band truncation's tail
is at most 7.2e-5 of the mean (``tools/irradiance_study.py``'s convergence table) and the lune rule converges
geometrically (32 nodes per panel within 1e-5); a wrong sun azimuth misses by percent (the negative control)."""

GROUND_TOL: float = 2e-4
"""The runtime's ground against brute force, of the mean irradiance, from 2 bands on: exact in SH; only E_h differs,
by the sun table's held-out error (<= 1e-4 of E_sun, and E_sun <= 4 x the mean) times albedo / 2 <= 1/2, plus the
sky table's c_10 fit error (far smaller)."""

WRONG_SCALE: float = 1.1
"""A deliberately wrong irradiance: the plain projection times 1.1 errs by 10% of the mean or more where the
irradiance is at least the mean (half the sphere facing the sky), above issue 18's 7% bound."""

LOWEST_SAMPLES: int = 20_000
"""Fibonacci directions of the sampled minimum that must not fall below the exact minimum (and nearly reaches it)."""

LOWEST_SAMPLED_GAP: float = 1e-3
"""The sampled minimum over 20,000 directions (spacing about 1.4 degrees) exceeds the exact minimum of a 3-band
function by at most its curvature times the squared half-spacing: well under 1e-3 of the mean for these skies."""


@functools.cache
def irradiance_64(sun_zenith: float, turbidity: float, sun_azimuth: float) -> np.ndarray:
    """sh.irradiance of preetham.sky_sh at 64 bands (4,096 coefficients), computed once per sky."""
    from skysh.model import preetham
    from skysh.sh import basis as sh

    return sh.irradiance(preetham.sky_sh(sun_zenith, turbidity, 64, sun_azimuth))


@pytest.fixture(scope="module")
def quick_ctx(report: types.SimpleNamespace, tmp_path_factory: pytest.TempPathFactory) -> object:
    from skysh.runtime import SkySH

    return report.common.Context(plan=report.plans.QUICK, out=tmp_path_factory.mktemp("sections_11_12"), jobs=1,
                                 progress=False, sky=SkySH.load())


@pytest.fixture(scope="module")
def solved_once(report: types.SimpleNamespace) -> Iterator[None]:
    """``irradiance_study.solve_job`` (a sky's optimum: a pure function of its truth and the objective) memoised for
    the module: section 11's fixture and the run without the runtime table solve the same 24 problems (6 skies x 4
    objectives), the second reads the first's (in one process). The latter's grid solve is not memoised."""
    study = report.s11_irradiance_table.study
    solve_job, solved = study.solve_job, {}

    def memoised(job: tuple[np.ndarray, object]) -> np.ndarray:
        truth, objective = job
        key = (np.ascontiguousarray(truth).tobytes(), objective)
        if key not in solved:
            solved[key] = solve_job(job)
        return solved[key].copy()

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(study, "solve_job", memoised)
        yield


@pytest.fixture(scope="module")
def section_11(report: types.SimpleNamespace, quick_ctx: object, solved_once: None,
               tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, object]:
    s11 = report.s11_irradiance_table
    with pytest.MonkeyPatch.context() as patch:  # no dependence on the study's cache in build/
        patch.setattr(s11, "STUDY_GRID_CACHE", tmp_path_factory.mktemp("no_study_cache"))
        data = s11.compute(quick_ctx)
    return data, s11.render(quick_ctx, data)


@pytest.fixture(scope="module")
def section_12(report: types.SimpleNamespace, quick_ctx: object) -> tuple[dict, object]:
    s12 = report.s12_scene_irradiance
    data = s12.compute(quick_ctx)
    return data, s12.render(quick_ctx, data)


def section_checks(ctx: object, section: object, png: str, header: str) -> str:
    """The section's markdown has its heading, a table with ``header`` and its chart, a valid PNG on disk."""
    text = "\n".join(section.lines)  # type: ignore[attr-defined]
    assert text.startswith(f"## {section.number}. {section.title}")  # type: ignore[attr-defined]
    assert f"| {header} |" in text and f"]({png})" in text
    width, height = check_png(ctx.out / png)  # type: ignore[attr-defined]
    assert width >= 600 and height >= 300
    assert "nan" not in text.lower().split()
    return text


class TestIrradianceTableSection:
    @needs_cvxpy
    def test_table_chart_and_rows(self, section_11: tuple[dict, object], quick_ctx: object,
                                  report: types.SimpleNamespace) -> None:
        data, section = section_11
        text = section_checks(quick_ctx, section, "s11_irradiance_table.png", "3-band irradiance")
        study = report.s11_irradiance_table.study
        for name in data["results"]:
            assert f"| {name} |" in text
        assert {study.PLAIN, study.runtime_name(False), study.runtime_name(True)} <= set(data["results"])
        assert sum(name.startswith("tabulated: ") for name in data["results"]) == 1
        assert len(data["results"]) == 10  # plain, 2 runtime, continuous, whole rows, 4 optima, tabulated

    @needs_cvxpy
    def test_the_tabulated_row_meets_the_bound_and_stays_non_negative(self, section_11: tuple[dict, object],
                                                                       report: types.SimpleNamespace) -> None:
        data, _ = section_11
        tab = data["tabulated"]
        assert data["results"][tab["name"]]["error"].max() <= report.s11_irradiance_table.THRESHOLD
        assert tab["negative"] == 0 and tab["minimum"] >= 0.0

    @needs_cvxpy
    def test_negative_control_gibbs_exceeds_the_bound(self, section_11: tuple[dict, object],
                                                      report: types.SimpleNamespace) -> None:
        data, _ = section_11
        s11 = report.s11_irradiance_table
        assert data["results"][s11.study.runtime_name(True)]["error"].max() > s11.THRESHOLD

    def test_a_wrong_method_exceeds_the_bound_and_lowest_is_the_minimum(self, report: types.SimpleNamespace) -> None:
        from skysh.sh import basis as sh

        study = report.s11_irradiance_table.study
        ev = study.Evaluator(study.sky_points((30.0, 85.0), (3.0,)), None, 12, 16, log=lambda message: None,
                             truth_nodes=16)
        plain = ev.truth["coeffs"][:, :9]
        assert ev.measure(WRONG_SCALE * plain)["error"].min() > report.s11_irradiance_table.THRESHOLD
        sampled = np.min(np.einsum("mk,skc->smc", sh.basis(fibonacci_sphere(LOWEST_SAMPLES), 3), plain), axis=1)
        sampled = np.min(sampled / ev.mean, axis=1)
        lowest = ev.measure(plain)["lowest"]
        assert np.all(lowest <= sampled) and np.all(sampled - lowest <= LOWEST_SAMPLED_GAP)

    @needs_cvxpy
    def test_without_the_runtime_table_a_grid_is_solved_and_fitted(self, report: types.SimpleNamespace, quick_ctx: object,
                                                                   solved_once: None, tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
        s11 = report.s11_irradiance_table
        monkeypatch.setattr(s11, "STUDY_GRID_CACHE", tmp_path)
        monkeypatch.setattr(s11.study, "runtime_has_irradiance_table", lambda sky: False)
        data = s11.compute(quick_ctx)
        tab = data["tabulated"]
        assert "grid solve in this run" in tab["source"] and tab["name"] in data["results"]
        assert tab["points"] == s11.SIZES["quick"].nonneg_points + 4 + 4 * s11.SIZES["quick"].nonneg_per_edge
        assert not list(tmp_path.iterdir())  # the quick run caches nothing

    def test_continuous_window_at_the_table_sizes_is_the_table(self, report: types.SimpleNamespace) -> None:
        from skysh.post import dering

        study = report.s11_irradiance_table.study
        rows = study.continuous_window(np.array(dering.SEED_WINDOW_SIZES))
        np.testing.assert_allclose(rows, dering.window_table(3), rtol=0.0, atol=WINDOW_EXACT)

    def test_the_runtime_table_is_detected_by_its_option_and_file_table(self, report: types.SimpleNamespace) -> None:
        study = report.s11_irradiance_table.study

        class Runtime:
            def __init__(self, tables: dict) -> None:
                self.table = types.SimpleNamespace(tables=tables)

        class Old(Runtime):
            def coefficients(self, sun_zenith: float, turbidity: float, bands: int = 3) -> None: ...

        class New(Runtime):
            def coefficients(self, sun_zenith: float, turbidity: float, irradiance_table: bool | None = None) -> None: ...

        assert not study.runtime_has_irradiance_table(Old({"irradiance": 0}))
        assert not study.runtime_has_irradiance_table(New({"sun": 0}))
        assert study.runtime_has_irradiance_table(New({"irradiance": 0}))


class TestSceneIrradianceSection:
    def test_table_and_chart(self, section_12: tuple[dict, object], quick_ctx: object,
                             report: types.SimpleNamespace) -> None:
        data, section = section_12
        s12 = report.s12_scene_irradiance
        text = section_checks(quick_ctx, section, "s12_scene_irradiance.png", " | ".join(["bands", *s12.PARTS]))
        for bands in s12.BANDS:
            assert f"\n| {bands} | " in text
        assert data["errors"].shape == (len(s12.SIZES["quick"].scenes), len(s12.BANDS), len(s12.PARTS), 2)
        assert np.all(np.isfinite(data["errors"])) and np.all(data["errors"] >= 0.0)
        assert "Which part holds the worst error: N = " in text

    def test_more_bands_err_less(self, section_12: tuple[dict, object], report: types.SimpleNamespace) -> None:
        data, _ = section_12
        total = report.s12_scene_irradiance.PARTS.index("total")
        worst = data["errors"][:, :, total, 0]
        assert np.all(worst[:, -1] < worst[:, 0])  # 7 bands against 1 band, every scene

    @pytest.mark.parametrize("sign", [1.0, -1.0])
    def test_lune_rule_integrates_unit_radiance(self, report: types.SimpleNamespace, sign: float) -> None:
        s12 = report.s12_scene_irradiance
        normals = np.concatenate([fibonacci_sphere(101), [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
        if sign > 0:
            got = s12.lune_rule(normals, np.array([0.3, 0.4, math.sqrt(0.75)]), 12)[1].sum(axis=1)
        else:
            got = s12.ground_view(normals, 12)
        np.testing.assert_allclose(got, 0.5 * math.pi * (1.0 + sign * normals[:, 2]), rtol=0.0, atol=LUNE_EXACT)

    @pytest.mark.parametrize(("sun_zenith", "azimuth_error"), [(1.2, 0.0), (1.2, 0.5)])
    def test_brute_force_sky_against_the_64_band_projection(self, report: types.SimpleNamespace, sun_zenith: float,
                                                            azimuth_error: float) -> None:
        from skysh.sh import basis as sh

        s12 = report.s12_scene_irradiance
        normals = fibonacci_sphere(96)
        brute = s12.sky_irradiance(normals, sun_zenith, 3.5, s12.SUN_AZIMUTH + azimuth_error, 32)
        projected = irradiance_64(sun_zenith, 3.5, s12.SUN_AZIMUTH)  # the same sky for both cases
        values = sh.basis(normals, 64) @ projected
        error = np.max(np.abs(brute - values) / (projected[0] * 0.5 / math.sqrt(math.pi)))
        assert (error <= BRUTE_VS_SH) == (azimuth_error == 0.0), f"error {error:.2e} of the mean"

    def test_ground_is_exact_and_a_wrong_albedo_is_caught(self, report: types.SimpleNamespace, quick_ctx: object) -> None:
        from skysh.sh import basis as sh

        s12 = report.s12_scene_irradiance
        scene = s12.SIZES["quick"].scenes[1]
        normals, weights = sh.quadrature_rule(8)
        truth = s12.scene_truth(scene, normals, 16)
        ground = s12.PARTS.index("ground")
        wrong = s12.Scene(scene.sun_zenith_deg, scene.turbidity, tuple(min(1.0, a + 0.05) for a in scene.albedo))
        for bands in (2, 3, 7):
            right = s12.errors(s12.runtime_parts(quick_ctx, scene, normals, bands), truth, weights)[ground, 0]
            off = s12.errors(s12.runtime_parts(quick_ctx, wrong, normals, bands), truth, weights)[ground, 0]
            assert right <= GROUND_TOL < 100 * GROUND_TOL < off, (bands, right, off)


# --------------------------------------------------------------------------- #
# Section 13, in process at the quick sizes
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def section_13(report: types.SimpleNamespace, quick_ctx: object) -> tuple[dict, object]:
    s13 = report.s13_hosek
    data = s13.compute(quick_ctx)
    return data, s13.render(quick_ctx, data)


class TestHosekSection:
    def test_tables_and_charts(self, section_13: tuple[dict, object], quick_ctx: object,
                               report: types.SimpleNamespace) -> None:
        data, section = section_13
        s13 = report.s13_hosek
        text = section_checks(quick_ctx, section, "s13_rule_cost.png", "rule | zenith nodes + sun | rings")
        for k in range(len(data["pictures"])):
            width, height = check_png(quick_ctx.out / f"s13_skies_{k + 1}.png")  # type: ignore[attr-defined]
            assert f"](s13_skies_{k + 1}.png)" in text and width >= 600 and height >= 300
        assert len(data["pictures"]) == len(report.plans.QUICK.picture_suns)
        for rule in s13.candidates():
            assert f"\n| {rule} | " in text or f'\n| "{rule}" | ' in text
        sizes = s13.SIZES["quick"]
        assert data["curve"]["points"] == {"random": sizes.random + 16, "stress": len(range(0, 96, sizes.stress_step))}

    def test_the_curve_spans_the_targets(self, section_13: tuple[dict, object], report: types.SimpleNamespace) -> None:
        # the finest rule meets the targets by far, the coarsest misses them; the offered default meets them
        # (as tests/model/test_hosek_frame.py checks on its own sample), and every time is a positive duration
        curve, study = section_13[0]["curve"], report.s13_hosek.study
        rules = list(curve["rules"])
        assert rules[0] == "coarser" and rules[-1] == "finest"
        for bands in study.RULE_BANDS:
            target = study.RULE_TARGETS[bands]
            for name in ("random", "stress"):
                errors = {rule: curve["errors"][(rule, bands, name)] for rule in ("finest", "coarser")}
                assert errors["finest"] < target / 10 < 10 * target < errors["coarser"]
                assert curve["errors"][("default", bands, name)] <= target
        assert all(0.0 < t < 1.0 for t in curve["seconds"].values())

    def test_pictures_numbers(self, section_13: tuple[dict, object]) -> None:
        for item in section_13[0]["pictures"]:
            assert math.isfinite(item["exposure"]) and item["exposure"] > 0.0
            for model, numbers in item["numbers"].items():
                assert numbers["mean"] > 0.0, model
                assert numbers[7][0] < numbers[3][0], model  # 7 bands reconstruct the sky closer than 3

    def test_median_timing_calls_each_function_as_told(self, report: types.SimpleNamespace) -> None:
        calls = {"a": 0, "b": 0}

        def counter(key: str):
            def call() -> None:
                calls[key] += 1
            return call

        times = report.s13_hosek.interleaved_median({k: counter(k) for k in calls}, 3, 4)
        assert calls == {"a": 1 + 3 * 4, "b": 1 + 3 * 4} and set(times) == {"a", "b"}
        assert all(t >= 0.0 for t in times.values())
