"""
Screenshots of the viewer page at four settings, in headless Chromium
=====================================================================

    python tests/app/viewer_screenshots.py [OUT_DIR]      (default build/viewer-shots/)

Writes the page (:func:`skysh.app.viewer.write_static`), opens it from ``file://`` in
the system's Chromium through Playwright (no browser download), sets the controls
as a user would, and saves one full-page PNG per setting of :data:`SETTINGS`. It
prints, per page load, the time from navigation to the page's first frame
(``skyshViewer.startupMs``), the first load in a fresh browser separately: that
one includes starting the browser's GPU process.

``tests/app/test_viewer.py`` imports this file for its browser helpers
(:func:`find_chromium`, :func:`launch`, :func:`set_controls`) and runs
:func:`save_screenshots` in the test suite, so every test run refreshes the shots.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO: Path = Path(__file__).resolve().parents[2]
DEFAULT_OUT: Path = REPO / "build" / "viewer-shots"
"""Where the screenshots go (``build/`` is git-ignored)."""

CHROMIUM_CANDIDATES: tuple[str, ...] = (
    "/usr/lib/chromium/chromium",  # Debian's binary (/usr/bin/chromium is a shell wrapper around it)
    "chromium",
    "chromium-browser",
    "google-chrome",
)
"""Where the system's Chromium is looked for when ``SKYSH_CHROMIUM`` is not set (when it is, only there)."""

CHROMIUM_ARGS: tuple[str, ...] = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader")
"""Headless WebGL2 on the CPU (SwiftShader through ANGLE): deterministic, no GPU needed."""

VIEWPORT: dict[str, int] = {"width": 1400, "height": 1000}
"""Browser window size, CSS pixels (device scale 1)."""

READY: str = "() => globalThis.skyshViewer && skyshViewer.startupMs !== null"
"""True once the page has drawn its first frame (a function: the page's CSP forbids eval of a string)."""

PAGE_TIMEOUT_MS: int = 60_000
"""How long a page may take to draw its first frame (software WebGL on a shared machine)."""

SETTINGS: dict[str, dict[str, Any]] = {
    "midday": {"sun-zenith": 20.0, "sun-azimuth": 30.0, "turbidity": 3.0, "bands": 3},
    "sunset": {"sun-zenith": 88.0, "sun-azimuth": -120.0, "turbidity": 2.5, "bands": 7, "gibbs": False},
    "hazy-engine": {"sun-zenith": 60.0, "sun-azimuth": 135.0, "turbidity": 6.0, "bands": 3, "ev": 1.0,
                    "engine": "threejs", "readout-format": "snippet"},
    "hosek-low-sun": {"model": "hosek-wilkie", "sun-zenith": 84.0, "sun-azimuth": -60.0, "turbidity": 4.0,
                      "albedo": 0.3, "bands": 5},
}
"""Four settings (control id -> value) that show the page's range: a clear midday sky, a sunset
with 7 bands and no Gibbs filter (ringing below the horizon), a hazy sky with an engine snippet,
and the Hosek-Wilkie sky with a low sun over a ground of albedo 0.3."""


def find_chromium() -> str | None:
    """The system Chromium's executable, or None when there is none."""
    override = os.environ.get("SKYSH_CHROMIUM")
    for candidate in (override,) if override else CHROMIUM_CANDIDATES:
        path = candidate if os.path.isabs(candidate) else shutil.which(candidate)
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def launch(playwright: Any, executable: str) -> Any:
    """Headless Chromium through Playwright, with software WebGL2."""
    return playwright.chromium.launch(executable_path=executable, headless=True, args=list(CHROMIUM_ARGS))


def open_page(browser: Any, url: str) -> Any:
    """A new page at ``url``, after its first frame."""
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(url)
    page.wait_for_function(READY, timeout=PAGE_TIMEOUT_MS)
    return page


FIRST: tuple[str, ...] = ("model", "engine", "irradiance", "bands")
"""Controls set before the others: they change the defaults (the intent) or what the others allow (the model: the
turbidity's range, the albedo, the engine presets)."""

SELECTS: tuple[str, ...] = ("model", "engine", "readout-format")
"""The page's select controls (set by option value); the other non-checkbox controls are range inputs."""


def _current(page: Any, ids: list[str]) -> dict[str, Any]:
    return page.evaluate("""(ids) => Object.fromEntries(ids.map((id) => {
        const el = document.getElementById(id);
        return [id, el.type === "checkbox" ? el.checked : el.value];
    }))""", ids)


def set_controls(page: Any, values: dict[str, Any]) -> dict[str, Any]:
    """
    Set controls by id as a user would (fill, check, select) where they differ, then wait for
    the frame; the page's state. A disabled control cannot be changed (as by a user).
    """
    first = [key for key in FIRST if key in values]
    for group in (first, [key for key in values if key not in FIRST]):
        current = _current(page, group)
        for key in group:
            value, control = values[key], page.locator(f"#{key}")
            if isinstance(value, bool):
                if value != current[key]:
                    control.set_checked(value)
            elif key in SELECTS:
                if value != current[key]:
                    control.select_option(value)
            elif float(value) != float(current[key]):
                control.fill(str(value))
    page.evaluate("skyshViewer.nextFrame()")
    return page.evaluate("skyshViewer.state()")


def save_screenshots(browser: Any, url: str, out_dir: Path) -> dict[str, float]:
    """One full-page PNG per setting into ``out_dir``; {setting: first-frame ms of its page load}."""
    out_dir.mkdir(parents=True, exist_ok=True)
    startup = {}
    for name, values in SETTINGS.items():
        page = open_page(browser, url)
        startup[name] = page.evaluate("skyshViewer.startupMs")
        set_controls(page, values)
        page.screenshot(path=str(out_dir / f"{name}.png"), full_page=True)
        page.close()
    return startup


def main(argv: list[str] | None = None) -> int:
    from playwright.sync_api import sync_playwright

    from skysh.app.viewer import write_static

    args = sys.argv[1:] if argv is None else argv
    out_dir = Path(args[0]) if args else DEFAULT_OUT
    executable = find_chromium()
    if executable is None:
        print("no Chromium found (apt-get install chromium, or set SKYSH_CHROMIUM)", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as folder, sync_playwright() as playwright:
        write_static(folder)
        url = (Path(folder) / "index.html").as_uri()
        browser = launch(playwright, executable)
        first = open_page(browser, url)
        print(f"first load in a fresh browser: first frame {first.evaluate('skyshViewer.startupMs'):.0f} ms after navigation")
        first.close()
        startup = save_screenshots(browser, url, out_dir)
        browser.close()
    for name, ms in startup.items():
        print(f"{name}: first frame {ms:.0f} ms after navigation; {out_dir / (name + '.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
