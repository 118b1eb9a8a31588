"""
Tests of the JavaScript module's per-frame kernel (issue 26): its recurrences and its allocation-free options.

The module takes cos and sin of k phi (the Z rotation, Habel eq. 4) and of k ts (the sun's
trigonometric polynomial) by angle addition from one cos and one sin, and the ground's
albedo without allocating. Here, in node through ``test_export_js``'s :class:`NodeServer`:

-   the rotation's factors, read off the module's own output (the m = +k and m = -k
    coefficients at phi over the m = +k one at phi = 0, Gibbs off, no lights), against
    ``math.cos`` and ``math.sin`` of k phi for k up to 6 (7 bands), azimuths far beyond
    2 pi included; a negative control (the sine's sign) misses by far;
-   the sun's part (the call with ``sun`` less the call without) against the trigonometric
    polynomial of the module's data evaluated with numpy's cos and sin of k ts, at 3 and 7
    bands (the polynomial is cut at the call's band count), rotated by numpy's cos and sin;
-   the ``groundAlbedo`` option: a number, a list and a Float64Array agree; the caller's array is
    read per call, not kept; its refusals (wrong type, length, a hole, out of range) unchanged.

Skipped without node. Never timed: the timing is ``benchmarks/bench_js_floor.py``'s.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import SKIP_NO_NODE
from test_export_js import NODE, NodeServer

from skysh import SkySH
from skysh.export.js import module_data, module_source

pytestmark = [pytest.mark.skipif(NODE is None, reason=SKIP_NO_NODE), pytest.mark.integration]

ROTATION_TOLERANCE: float = 1e-14
"""|factor - cos(k phi)| (and sin) for k <= 6: the recurrence's error grows about one rounding of each of its two
products and one sum per step (k = 6: ~1e-15), read through two roundings of the product and the quotient."""

SUN_TOLERANCE: float = 1e-13
"""The sun's part against numpy, over |DC| of the same channel of the whole result (the tests' measure): the
recurrence against numpy's cos/sin of k ts (a few ulps), the subtraction's rounding at the scale of the whole
result, and ``sunLight``'s RGB read back from its printed doubles (exact)."""

CONTROL_MARGIN: float = 1e3
"""A negative control misses by this factor times the tolerance."""

AZIMUTHS: tuple[float, ...] = (0.3, 1.0, 2.5, -2.0, 3.14159, 7.0, -40.0, 1.0e3)
"""Azimuths of the rotation test (radians): each quadrant, near pi, and far beyond 2 pi (the module reduces
with %, as math.fmod)."""

FRAMES: tuple[tuple[float, float, float], ...] = ((0.2, 2.5, 0.7), (0.9, 3.0, -1.3), (1.45, 5.5, 2.9), (1.5707, 6.0, 4.0))
"""(sun zenith, turbidity, azimuth) of the sun tests: high, middle, low and at the horizon."""


@pytest.fixture(scope="module")
def kernel_dir(sky: SkySH, tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("js_kernel")
    (directory / "sky_sh.mjs").write_text(module_source(sky))
    return directory


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Any:
    node = NodeServer(tmp_path_factory.mktemp("node_kernel"))
    yield node
    node.close()


@pytest.fixture(scope="module")
def data(sky: SkySH) -> dict[str, Any]:
    return json.loads(module_data(sky))


def values(answer: dict[str, Any]) -> list[np.ndarray]:
    """The calls' results as arrays; a thrown error fails the test with its message."""
    out = []
    for result in answer["results"]:
        assert "error" not in result, result
        out.append(np.asarray(result["values"], dtype=float))
    return out


def rotation_errors(server: NodeServer, folder: Path) -> tuple[float, float]:
    """The worst |factor - cos, sin(k phi)| over AZIMUTHS, k = 1..6, channels; and the control's (sin's sign)."""
    options = {"bands": 7, "gibbs": False}
    calls = [[0.8, 3.0, 0.0, options]] + [[0.8, 3.0, phi, options] for phi in AZIMUTHS]
    base, *rotated = values(server.run(folder, calls))
    worst = control = 0.0
    for phi, c in zip(AZIMUTHS, rotated):
        p = math.fmod(phi, 2.0 * math.pi)
        for l in range(1, 7):
            for k in range(1, l + 1):
                plus, minus, ref = 3 * (l * (l + 1) + k), 3 * (l * (l + 1) - k), base[3 * (l * (l + 1) + k):][:3]
                cos, sin = c[plus:plus + 3] / ref, c[minus:minus + 3] / ref
                worst = max(worst, *np.abs(cos - math.cos(k * p)), *np.abs(sin - math.sin(k * p)))
                control = max(control, *np.abs(sin + math.sin(k * p)))
    return worst, control


def test_rotation_recurrence(server: NodeServer, kernel_dir: Path) -> None:
    worst, control = rotation_errors(server, kernel_dir)
    assert worst <= ROTATION_TOLERANCE, worst
    assert control > CONTROL_MARGIN * ROTATION_TOLERANCE, control  # the other handedness is far off


def sun_reference(data: dict[str, Any], ts: float, phi: float, n: int, rgb: np.ndarray) -> np.ndarray:
    """The sun's n-band SH (flat, coefficient-major RGB) from the module's data: its trigonometric polynomial cut at
    n, windowed, with numpy's cos and sin of q ts, rotated by numpy's cos and sin of k phi, times the clamped RGB."""
    lights, mb = data["lights"], data["maxBands"]
    trig, windows, g0 = np.asarray(lights["trig"]), lights["windows"], n * (n - 1) // 2
    q = np.arange(n)
    out = np.zeros((n * n, 3))
    light = np.maximum(rgb, lights["constants"]["clamp"])
    for l in range(n):
        for k in range(l + 1):
            r = (l * (l + 1) // 2 + k) * 2 * mb
            y = windows[g0 + l] * (trig[r:r + n] @ np.cos(q * ts) + trig[r + mb:r + mb + n] @ np.sin(q * ts))
            out[l * (l + 1) + k] = y * (math.cos(k * phi) if k else 1.0) * light
            if k:
                out[l * (l + 1) - k] = y * math.sin(k * phi) * light
    return out.ravel()


def sun_errors(server: NodeServer, folder: Path, data: dict[str, Any]) -> float:
    """The worst error of the module's sun part (sun on less off) against :func:`sun_reference`, over FRAMES, 3 and 7
    bands, over |DC| of the same channel of the whole result."""
    worst = 0.0
    for n in (3, 7):
        calls: list[list[Any]] = []
        for ts, t, phi in FRAMES:
            calls += [[ts, t, phi, {"bands": n, "sun": True}], [ts, t, phi, {"bands": n}], ["sunLight", ts, t, phi]]
        results = values(server.run(folder, calls))
        for i, (ts, _, phi) in enumerate(FRAMES):
            lit, dark, light = results[3 * i: 3 * i + 3]
            reference = sun_reference(data, ts, math.fmod(phi, 2.0 * math.pi), n, light[3:])
            dc = np.abs(np.tile(lit[:3], n * n))
            worst = max(worst, float(np.max(np.abs(lit - dark - reference) / dc)))
    return worst


def test_sun_recurrence(server: NodeServer, kernel_dir: Path, data: dict[str, Any]) -> None:
    assert sun_errors(server, kernel_dir, data) <= SUN_TOLERANCE


def test_ground_albedo_forms(server: NodeServer, kernel_dir: Path) -> None:
    """A number, a list and a Float64Array give the same result; the caller's array is read at every call."""
    frame = [0.7, 3.0, 1.0]
    options = [{"bands": 3, "groundAlbedo": 0.25}, {"bands": 3, "groundAlbedo": [0.25, 0.25, 0.25]},
               {"bands": 3, "groundAlbedo": [0.1, 0.5, 0.9]}, {"bands": 3}, {"bands": 3, "groundAlbedo": [0.0, 0.0, 0.0]}]
    same, list_, rgb, black, zero = values(server.run(kernel_dir, [frame + [o] for o in options]))
    assert np.array_equal(same, list_)
    assert np.array_equal(black, zero)  # black: no ground
    assert not np.array_equal(rgb, same) and not np.array_equal(black, same)
    # After a call with one albedo, the next with another reads its own (no albedo kept between calls).
    again = values(server.run(kernel_dir, [frame + [options[2]], frame + [options[0]], frame + [options[3]]]))
    assert np.array_equal(again[0], rgb) and np.array_equal(again[1], same) and np.array_equal(again[2], black)


REFUSALS: tuple[tuple[Any, str, str], ...] = (
    ("0.2", "TypeError", "groundAlbedo must be a number or an array of 3 numbers"),
    ([0.2, 0.2], "TypeError", "groundAlbedo must be a number or an array of 3 numbers"),
    ([0.2, "0.2", 0.2], "TypeError", "groundAlbedo must be a number or an array of 3 numbers"),
    ([0.2, None, 0.2], "TypeError", "groundAlbedo must be a number or an array of 3 numbers"),
    (1.5, "RangeError", "groundAlbedo must lie in [0, 1] per channel, got 1.5, 1.5, 1.5"),
    ([0.2, -0.1, 0.2], "RangeError", "groundAlbedo must lie in [0, 1] per channel, got 0.2, -0.1, 0.2"),
    ({"$float": "NaN"}, "RangeError", "groundAlbedo must lie in [0, 1] per channel, got NaN, NaN, NaN"),
)
"""(groundAlbedo, the error's class, its message's start): the refusals as the module words them."""


def test_ground_albedo_refusals(server: NodeServer, kernel_dir: Path) -> None:
    calls = [[0.7, 3.0, 1.0, {"groundAlbedo": value}] for value, _, _ in REFUSALS]
    for (value, kind, message), result in zip(REFUSALS, server.run(kernel_dir, calls)["results"]):
        assert result.get("error") == kind and result["message"].startswith(message), (value, result)
