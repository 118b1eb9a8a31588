"""
The interactive viewer page: the sky, its SH reconstruction and the lighting, live
==================================================================================

-   :func:`page_files`: the page's files in memory (name -> bytes).
-   :func:`write_static`: write them to a folder (``skysh view --out DIR``); the
    page then works from any static server and from ``file://``.
-   :func:`make_server`, :func:`serve`: serve them on loopback only
    (``skysh view``): a silent connection is closed after :data:`IDLE_TIMEOUT_S`, at most
    :data:`MAX_CONNECTIONS` are handled at once (one thread each; the others wait in the
    listen backlog), and a client that goes away early is not reported.
-   :data:`PAGE_FILES`, :data:`LOOPBACK_HOSTS`, :data:`IDLE_TIMEOUT_S`, :data:`MAX_CONNECTIONS`,
    :data:`LISTEN_BACKLOG`, :data:`CONNECTION_THREAD`.

The page (``skysh/app/web/``) is WebGL2 and plain JavaScript: no framework, no CDN,
no request beyond its own files (its Content-Security-Policy forbids any other).
It shows one of two skies, switched on the page: the Preetham sky (the coefficient file's
runtime) or the Hosek-Wilkie sky (its per-frame runtime, sky only: no sun disk, black below
the horizon). Everything it computes comes from skysh, generated when the files are written:

-   The per-frame coefficients come from two JavaScript runtimes: the Preetham sky's from
    :func:`skysh.export.c_like.export_source` (``"js"``, every band the coefficient file holds),
    with the Python runtime's defaults (the certified irradiance table for 3-band irradiance
    and engine presets; a box gives the old pipeline, ``irradiance_table=False``); the
    Hosek-Wilkie sky's from :func:`skysh.export.hosek.export_source` (``"js"``, as many bands,
    at most 7), the same numbers as ``SkySH.load(model="hosek-wilkie").coefficients``, at the
    page's grey ground albedo (one slider; the runtime also takes R, G, B). The scene's
    irradiance is the runtime's ``irradiance: true`` call, not A_l times the radiance shown.
    Each runtime is inlined into ``index.html`` as a ``<script type="module">`` of its own
    (the two modules' top-level names would clash in one) that hands its exports to
    ``viewer.js`` (``skyshViewer.register``; the page starts once both are in), each script
    allowed by its hash in the Content-Security-Policy: Chromium refuses module scripts loaded
    from ``file://`` (CORS), so the page loads no module file. Its classic scripts
    (``sky.js``, ``shaders.js``, ``viewer.js``) load from ``file://`` as from a server.
-   The controls follow the model: the turbidity slider spans the runtime's domain
    (Preetham [2.5, 6], Hosek-Wilkie [1, 10]; the value is clamped into it on a switch, so a
    value inside both is kept); the albedo slider shows for Hosek-Wilkie only; the engine
    presets and the certified-table box are off for it, with a note (its module has no engine
    map and there is no table; its deringing is available at every band count).
-   The true Preetham sky (1999, appendix), evaluated per pixel in the fragment
    shader and in double precision on the CPU, takes its constants from
    :mod:`skysh.model.preetham`: the Perez tables, the zenith-chromaticity matrices,
    and the XYZ -> RGB matrix of the coefficient file's colourspace; the zenith luminance
    is the exported JavaScript runtime's own (``zenithLuminance``, written once in
    ``skysh/export/templates/js_module.mjs``), handed to the page with the runtime.
-   The true Hosek-Wilkie sky (2012, eq. 9, linear sRGB: the model's RGB dataset) is drawn per
    pixel in the fragment shader from the parameters A..I and L_M x efficacy of the module's
    ``configuration()``, uniforms set per frame (L_M times the efficacy in double, then
    rounded once), and :data:`skysh.model.hosek.HORIZON_OFFSET` written into the shader from
    the page's configuration; zero below the horizon. On the CPU (the error numbers) it is
    the module's own ``radiance()``, in double.
-   The SH basis uses :mod:`skysh.sh.basis`'s recurrence constants; the tone mapping
    :mod:`skysh.app.render`'s key.
-   The engine snippets are :func:`skysh.engines.presets.snippet` turned into templates
    (:func:`snippet_templates`): one source of truth for their text.
-   The read-out (JSON or an engine's snippet; ``sky.js``'s ``readout``, no DOM) prints
    every number below 1e-12 of the DC term (the largest |coefficient of row 0| over the
    channels, of the radiance an engine converts) as 0, and -0 as 0: rounding noise of the
    rotation to the sun's azimuth (``sky.js``'s ``NOISE_FLOOR``; the rule of
    :func:`skysh.engines.presets.snippet`). Its JSON names the ``model`` (as ``skysh coeffs``
    does) and, for Hosek-Wilkie, the ``albedo``.

The page's error number is the relative RMS difference of the reconstructed
radiance from the true sky (of the model shown) over the upper hemisphere (all three
channels), computed on the CPU in double precision by a product rule (:data:`ERROR_RULE_MU`
Gauss-Legendre nodes in cos(theta) times :data:`ERROR_RULE_PHI` azimuths); the
ringing number is the RMS of the reconstruction below the horizon over the
same norm of the true sky above it.

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999). A Practical Analytic Model for
    Daylight. SIGGRAPH 1999, appendix.
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome Radiance.
    ACM Trans. Graph. 31(4), 95: eq. (9), section 5.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5).
-   Ramamoorthi, R., Hanrahan, P. (2001): the clamped-cosine factors A_l.
"""

from __future__ import annotations

import base64
import hashlib
import http.server
import ipaddress
import json
import math
import re
import socket
import sys
import threading
import webbrowser
from functools import partialmethod
from pathlib import Path
from string import Template
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import files
from skysh._version import __version__
from skysh.app import render
from skysh.engines import presets as engines
from skysh.export import hosek as hosek_export
from skysh.export.c_like import export_source
from skysh.lighting import sunlight
from skysh.literals import double_literal, suffixed_literal
from skysh.model import hosek, preetham
from skysh.runtime import SkySH
from skysh.sh import basis as sh

__all__ = []

WEB_DIR: Path = Path(__file__).with_name("web")
"""The page's source folder inside the package (shipped as package data)."""

PAGE_FILES: tuple[str, ...] = ("index.html", "viewer.css", "sky.js", "shaders.js", "viewer.js")
"""The files of the page: :func:`write_static` writes exactly these and :func:`serve` serves only these."""

_STATIC_SOURCES: tuple[str, ...] = ("viewer.css", "sky.js", "shaders.js", "viewer.js")
"""Files copied from :data:`WEB_DIR` unchanged; ``index.html`` is generated from its template."""

_CONTENT_TYPES: dict[str, str] = {".html": "text/html; charset=utf-8", ".css": "text/css; charset=utf-8",
                                   ".js": "text/javascript; charset=utf-8"}

_HEADERS: dict[str, str] = {"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff", "Referrer-Policy": "no-referrer"}
"""Headers of every answer besides its type, length and :data:`_CSP`: never cached, never sniffed, no referrer."""

LOOPBACK_HOSTS: tuple[str, ...] = ("127.0.0.1", "::1", "localhost")
"""Host names :func:`serve` accepts (any other address in 127.0.0.0/8 too); anything else is refused."""

IDLE_TIMEOUT_S: float = 5.0
"""Default seconds, > 0, that the server waits on a connection that sends nothing (no request, or half of one)
or reads nothing of its answer before it closes it; a browser's request arrives within milliseconds."""

MAX_CONNECTIONS: int = 16
"""Default number of connections handled at once, one thread each (a browser opens about six per server); the
next ones wait, connected, in the listen backlog until a handler is free."""

LISTEN_BACKLOG: int = 64
"""Connections the kernel holds while all handlers are busy; beyond it a client's connection attempt is dropped
(its TCP stack retries)."""

CONNECTION_THREAD: str = "skysh-viewer-connection"
"""Name of the server's handler threads (each handles one connection, then ends), followed by ``:PORT``."""

_SLOT_POLL_S: float = 0.25
"""Seconds between the accept loop's checks for ``shutdown()`` while every handler is busy."""

_EARLY_DISCONNECT: tuple[type[BaseException], ...] = (ConnectionError, TimeoutError)
"""A client that went away or stalled (BrokenPipeError, ConnectionResetError, ConnectionAbortedError, a socket
timeout): not the server's fault, so not reported."""

ERROR_RULE_MU: int = 24
"""Gauss-Legendre nodes in cos(theta) per hemisphere of the page's error rule."""

ERROR_RULE_PHI: int = 48
"""Equally spaced azimuths of the page's error rule (exact for trigonometric polynomials of degree < 48)."""

_SNIPPET_SEED: int = 16
"""Seed of the random radiance coefficients the snippet templates are read from (any seed works)."""

_CSP: str = ("default-src 'none'; script-src 'self' $script_hashes; style-src 'self'; img-src 'self' data:; "
             "connect-src 'none'; base-uri 'none'; form-action 'none'")
"""The page's Content-Security-Policy: its own files and its two inline module scripts, nothing else."""

_HANDOVER: dict[str, str] = {
    "preetham": "coefficients, engineLayout, ENGINES, MAX_BANDS, SKYSH_VERSION, SUN_ZENITH_DOMAIN, TURBIDITY_DOMAIN, "
                "zenithLuminance",
    "hosek-wilkie": "createSky, configuration, radiance, MAX_BANDS, SKYSH_VERSION, SUN_ZENITH_DOMAIN, TURBIDITY_DOMAIN, "
                    "ALBEDO_DOMAIN",
}
"""What each inlined runtime (model name -> its exports) hands to the viewer (viewer.js's ``skyshViewer.register``)."""


# --------------------------------------------------------------------------- #
# Constants generated from skysh
# --------------------------------------------------------------------------- #
_NUMBER_FORMATS: dict[str, Any] = {"js": double_literal, "f32": suffixed_literal}
"""How :func:`skysh.engines.presets.snippet` writes a number: ``js`` (JavaScript) the shortest round-trip text
(Python's repr), ``f32`` (C++ / C#) that text with the float suffix; the page's ``sky.js`` implements both."""

_NUMBER_TOKEN: re.Pattern[str] = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:e[+-]\d+)?f?(?![\w.])")
"""A number as a snippet writes it (with its sign and an optional float suffix)."""

_TEMPLATE_MATCH: float = 1e-12
"""A snippet number stands for engine value k when it is within this fraction of the largest
value of k's value: the snippet and :func:`skysh.engines.presets.convert` may round the same map
differently in the last bit; random values are never this close to each other."""


def _numbers(text: str) -> tuple[list[str], list[str], NDArray[np.float64]]:
    """
    Split a snippet at the numbers it writes in one of :data:`_NUMBER_FORMATS`.

    Returns
    -------
    parts, formats, values
        The text around the numbers (one more part than numbers), each number's format name
        and its value: ``parts[0] + number 0 + parts[1] + ...`` is ``text``.
    """
    parts, formats, values, last = [], [], [], 0
    for match in _NUMBER_TOKEN.finditer(text):
        token = match.group(0)
        value = float(token.rstrip("f"))
        name = next((name for name, fmt in _NUMBER_FORMATS.items() if fmt(value) == token), None)
        if name is not None:
            parts.append(text[last : match.start()])
            formats.append(name)
            values.append(value)
            last = match.end()
    parts.append(text[last:])
    return parts, formats, np.array(values)


def _same_snippet(a: str, b: str, scale: float) -> bool:
    """The same text and number formats, and numbers within ``scale`` of each other."""
    (pa, fa, va), (pb, fb, vb) = _numbers(a), _numbers(b)
    return pa == pb and fa == fb and bool(np.all(np.abs(va - vb) <= scale))


def _template(engine: str, bands: int, rng: np.random.Generator) -> str:
    """One snippet template: ``{{k:fmt}}`` where the k-th engine value is written with format fmt."""
    v1, v2 = rng.standard_normal((2, bands * bands, 3)) * 1000.0
    e1, e2 = (engines.convert(v, engine).ravel() for v in (v1, v2))
    scale = _TEMPLATE_MATCH * max(float(np.max(np.abs(np.concatenate([e1, e2])))), 1.0)
    parts, formats, values = _numbers(engines.snippet(v1, engine))
    where = {}  # number position in the snippet -> engine value index
    for k in np.flatnonzero(e1 != e2):  # outputs that depend on the coefficients (not the map's constants)
        found = np.flatnonzero(np.abs(values - e1[k]) <= scale)
        if len(found) != 1:
            raise RuntimeError(f"skysh.engines.presets.snippet({engine!r}) writes value {k} {len(found)} times; expected once")
        where[int(found[0])] = int(k)
    marks = [f"{{{{{where[i]}:{fmt}}}}}" if i in where else _NUMBER_FORMATS[fmt](value)
             for i, (fmt, value) in enumerate(zip(formats, values, strict=True))]
    template = parts[0] + "".join(mark + part for mark, part in zip(marks, parts[1:], strict=True))
    if not _same_snippet(fill_snippet(template, e2), engines.snippet(v2, engine), scale):
        raise RuntimeError(f"the snippet template of {engine!r} does not reproduce skysh.engines.presets.snippet")
    return template


def fill_snippet(template: str, values: NDArray[np.float64]) -> str:
    """A template of :func:`snippet_templates` with ``values`` (an engine's flattened numbers) in place."""
    return re.sub(r"\{\{(\d+):(\w+)\}\}", lambda m: _NUMBER_FORMATS[m.group(2)](values[int(m.group(1))]), template)


def snippet_templates(max_bands: int) -> dict[str, dict[str, str]]:
    """
    :func:`skysh.engines.presets.snippet` of every engine and band count as a template the page fills in.

    Parameters
    ----------
    max_bands
        Largest band count wanted (each engine gets 1 .. min(this, its limit)).

    Returns
    -------
    dict
        ``{engine: {str(bands): template}}``. In a template, ``{{k:js}}`` and ``{{k:f32}}``
        stand for the k-th number of the engine's flattened values (what the JS runtime's
        ``engine`` option returns) written as :data:`_NUMBER_FORMATS` says; everything else
        is the snippet's own text. Each template is checked: filled with a second set of
        values in Python, it must equal ``engines.snippet`` of those values.
    """
    rng = np.random.default_rng(_SNIPPET_SEED)
    return {
        engine: {str(n): _template(engine, n, rng) for n in range(1, min(max_bands, engines.ENGINE_MAX_BANDS[engine]) + 1)}
        for engine in engines.ENGINES
    }


def _error_rule() -> dict[str, list[float]]:
    """Gauss-Legendre nodes and weights on [0, 1] in cos(theta) (the upper hemisphere)."""
    nodes, weights = np.polynomial.legendre.leggauss(ERROR_RULE_MU)
    return {"mu": (0.5 * (nodes + 1.0)).tolist(), "weights": (0.5 * weights).tolist(), "azimuths": ERROR_RULE_PHI}


def _rgb_from_xyz(sky: SkySH) -> NDArray[np.float64]:
    """The file's XYZ -> linear RGB matrix: the one its sun table records (colour-science's for the file's
    colourspace, ``tests/lighting/test_sunlight.py``), so building the page needs no colour-science import; for a
    file without a sun table, colour-science's."""
    if "sun" in sky.table.tables:
        return np.asarray(sunlight.SunLight(sky.table).rgb_from_xyz, dtype=np.float64)
    return preetham.rgb_from_xyz_matrix(sky.colourspace)


def page_config(sky: SkySH) -> dict[str, Any]:
    """
    Everything the page's scripts take from skysh, as JSON-ready data (embedded in ``index.html``).

    Parameters
    ----------
    sky
        The loaded runtime whose coefficient file the page's runtime is exported from.
    """
    recurrence = sh.basis_recurrence(sky.bands)
    return {
        "version": __version__,
        "colourspace": sky.colourspace,
        "maxBands": sky.bands,
        "perez": {"x": preetham.PEREZ_X.tolist(), "y": preetham.PEREZ_YC.tolist(), "Y": preetham.PEREZ_Y.tolist()},
        "zenithX": preetham.ZENITH_X_MATRIX.tolist(),
        "zenithY": preetham.ZENITH_Y_MATRIX.tolist(),
        "xyzToRgb": _rgb_from_xyz(sky).tolist(),
        "shRecurrence": {"diag": recurrence.diag.tolist(), "a": recurrence.a.tolist(), "b": recurrence.b.tolist()},
        "lobe": sh.cosine_lobe(sky.bands).tolist(),
        "hosekHorizonOffset": hosek.HORIZON_OFFSET,
        "keyValue": render.KEY_VALUE,
        "errorRule": _error_rule(),
        "engines": list(engines.ENGINES),
        "engineMaxBands": dict(engines.ENGINE_MAX_BANDS),
        "snippets": snippet_templates(sky.bands),
    }


# --------------------------------------------------------------------------- #
# The files
# --------------------------------------------------------------------------- #
def page_files(sky: SkySH | None = None) -> dict[str, bytes]:
    """
    The page's files, generated in memory.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`; default the shipped coefficient file.

    Returns
    -------
    dict
        ``{name: content}`` for every name of :data:`PAGE_FILES`.
    """
    sky = SkySH.load() if sky is None else sky
    modules = {"preetham": export_source(sky, "js", bands=None),
               "hosek-wilkie": hosek_export.export_source("js", bands=min(sky.bands, hosek_export.MAX_EXPORT_BANDS))}
    scripts = {}
    for model, module in modules.items():
        if "</script" in module.lower() or "<!--" in module:  # text that would end the element early
            raise RuntimeError(f"the JavaScript runtime of {model} contains '</script' or '<!--' and cannot be inlined")
        scripts[model] = module + ("\n// The viewer (viewer.js, a classic script run before this module) takes the runtime from "
                                   f"here.\nglobalThis.skyshViewer.register({json.dumps(model)}, {{ {_HANDOVER[model]} }});\n")
    digests = (base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii") for text in scripts.values())
    hashes = " ".join(f"'sha256-{digest}'" for digest in digests)
    config = json.dumps(page_config(sky), separators=(",", ":"), allow_nan=False)
    index = Template((WEB_DIR / "index.html").read_text(encoding="utf-8")).substitute(
        csp=Template(_CSP).substitute(script_hashes=hashes), runtime=scripts["preetham"],
        hosek_runtime=scripts["hosek-wilkie"], version=__version__,
        config=config.replace("<", "\\u003c"))  # every '<' escaped: nothing can end the <script> element early
    return {"index.html": index.encode("utf-8"), **{name: (WEB_DIR / name).read_bytes() for name in _STATIC_SOURCES}}


def content_security_policy(index_html: bytes) -> str:
    """The Content-Security-Policy written in ``index.html``'s meta element (the server sends it too)."""
    match = re.search(rb'http-equiv="Content-Security-Policy" content="([^"]*)"', index_html)
    if match is None:
        raise RuntimeError("index.html has no Content-Security-Policy")
    return match.group(1).decode("ascii")


def write_static(out_dir: str | Path, sky: SkySH | None = None) -> list[Path]:
    """
    Write the page's files into ``out_dir`` (created if missing).

    Parameters
    ----------
    out_dir
        Folder to write into; files of :data:`PAGE_FILES` there are replaced,
        nothing else is touched.
    sky
        A loaded :class:`skysh.SkySH`; default the shipped coefficient file.

    Returns
    -------
    list of Path
        The files written; open ``index.html`` (``file://`` works) or serve the folder.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out_dir must be a folder, got the file {str(out)!r}")
    # all renamed into place only once every file is complete; a link there is replaced, never written through
    return files.write_together({out / name: content for name, content in page_files(sky).items()}, parents=True)


# --------------------------------------------------------------------------- #
# The server
# --------------------------------------------------------------------------- #
class _Handler(http.server.BaseHTTPRequestHandler):
    """GET / HEAD of the page's files from memory; 404 for any other path. One request per connection (HTTP/1.0);
    a connection silent for ``timeout`` seconds is closed (http.server drops it quietly). :func:`make_server`
    gives each server a subclass holding its ``files``, ``csp`` and ``timeout``."""

    server_version = "skysh-viewer"
    sys_version = ""
    files: dict[str, tuple[bytes, str]]  # name -> (content, Content-Type)
    csp: str  # the Content-Security-Policy header
    # ``timeout`` (seconds): socketserver's StreamRequestHandler sets it on the connection, every read and write

    def _host_allowed(self) -> bool:
        """Refuse a Host header naming anything but loopback (DNS-rebinding guard)."""
        host = self.headers.get("Host")
        if host is None:
            return True
        name = host.rsplit(":", 1)[0] if not host.endswith("]") else host
        try:
            _loopback(name.strip("[]"))
        except ValueError:
            return False
        return True

    def _respond(self, body: bool) -> None:
        path = self.path.split("?", 1)[0].split("#", 1)[0]
        name = "index.html" if path == "/" else path[1:] if path.startswith("/") else ""
        entry = self.files.get(name)
        if not self._host_allowed():
            self._send(403, b"forbidden host\n", "text/plain; charset=utf-8", body)
        elif entry is None:  # exact names only: no listing, no '..', no encoded or absolute paths
            self._send(404, b"not found\n", "text/plain; charset=utf-8", body)
        else:
            self._send(200, *entry, body)

    def _send(self, status: int, content: bytes, content_type: str, body: bool) -> None:
        self.send_response(status)
        headers = {"Content-Type": content_type, "Content-Length": str(len(content)), **_HEADERS,
                   "Content-Security-Policy": self.csp}
        for key, value in headers.items():
            self.send_header(key, value)
        self.end_headers()
        if body:
            self.wfile.write(content)

    do_GET = partialmethod(_respond, True)  # http.server's names: GET answers with the body, HEAD without
    do_HEAD = partialmethod(_respond, False)

    def log_message(self, format: str, *args: Any) -> None:  # http.server's signature
        pass  # quiet: the command prints its address and nothing per request


class _Server(http.server.ThreadingHTTPServer):
    """A thread per connection, at most ``max_connections`` at once; a client's early disconnect is not reported."""

    daemon_threads = True  # Ctrl-C does not wait for open connections
    request_queue_size = LISTEN_BACKLOG

    def __init__(self, address: tuple[str, int], handler: Any, max_connections: int) -> None:
        self._slots = threading.BoundedSemaphore(max_connections)
        self._stopping = threading.Event()
        self.address_family = socket.AF_INET6 if ":" in address[0] else socket.AF_INET  # the socket is made next
        super().__init__(address, handler)

    def process_request(self, request: Any, client_address: Any) -> None:
        """Start the connection's thread once a slot is free; meanwhile the accept loop waits (new connections wait
        in the backlog) and gives the connection up when ``shutdown()`` is called."""
        while not self._slots.acquire(timeout=_SLOT_POLL_S):
            if self._stopping.is_set():
                self.shutdown_request(request)
                return
        name = f"{CONNECTION_THREAD}:{self.server_address[1]}"
        thread = threading.Thread(target=self._handle, args=(request, client_address), name=name, daemon=True)
        try:
            thread.start()  # from here the thread owns the slot (its _handle releases it)
        except RuntimeError:  # "can't start new thread": it never ran, so the slot is still ours
            self._slots.release()
            raise
        # A KeyboardInterrupt (Ctrl-C) can arrive while start() waits for the thread to begin: the thread may
        # already run and will release its slot, so it is not released here (that released it twice, and the
        # ValueError hid the Ctrl-C: the server kept running).

    def _handle(self, request: Any, client_address: Any) -> None:
        try:
            self.process_request_thread(request, client_address)  # handles, reports errors, closes the socket
        finally:
            self._slots.release()

    def handle_error(self, request: Any, client_address: Any) -> None:
        """socketserver's traceback on stderr, except for a client that went away (:data:`_EARLY_DISCONNECT`)."""
        if not isinstance(sys.exc_info()[1], _EARLY_DISCONNECT):
            super().handle_error(request, client_address)

    def shutdown(self) -> None:
        self._stopping.set()
        super().shutdown()


def _loopback(host: str) -> str:
    """The numeric loopback address of ``host``, or a ValueError."""
    if isinstance(host, str) and host.lower() == "localhost":
        return "127.0.0.1"
    try:
        address = ipaddress.ip_address(host) if isinstance(host, str) else None
    except ValueError:
        address = None
    if address is None or not address.is_loopback:
        raise ValueError(f"host must be a loopback address ({', '.join(LOOPBACK_HOSTS)}), got {host!r}")
    return str(address)


def _check_limits(port: int, timeout: float, max_connections: int) -> None:
    """ValueError naming the parameter of :func:`make_server` that is out of its range."""
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"port must be an integer in [0, 65535], got {port!r}")
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0.0 < timeout < math.inf:
        raise ValueError(f"timeout must be a finite number of seconds > 0, got {timeout!r}")
    if isinstance(max_connections, bool) or not isinstance(max_connections, int) or max_connections < 1:
        raise ValueError(f"max_connections must be an integer >= 1, got {max_connections!r}")


def make_server(host: str = "127.0.0.1", port: int = 0, sky: SkySH | None = None, timeout: float = IDLE_TIMEOUT_S,
                max_connections: int = MAX_CONNECTIONS) -> http.server.ThreadingHTTPServer:
    """
    A bound (not yet running) HTTP server of the page on loopback.

    Parameters
    ----------
    host
        A loopback address (:data:`LOOPBACK_HOSTS`, or any in 127.0.0.0/8).
    port
        TCP port in [0, 65535]; 0 picks a free one (read ``server.server_address``).
    sky
        A loaded :class:`skysh.SkySH`; default the shipped coefficient file.
    timeout
        Seconds, finite and > 0 (default :data:`IDLE_TIMEOUT_S`): a connection that sends nothing, stops part
        way through its request or takes nothing of the answer for this long is closed.
    max_connections
        Connections handled at once, an integer >= 1 (default :data:`MAX_CONNECTIONS`): one thread each
        (named :data:`CONNECTION_THREAD` ``:PORT``); the next ones wait in the listen backlog (:data:`LISTEN_BACKLOG`).

    Returns
    -------
    ThreadingHTTPServer
        Run it with ``serve_forever()``; stop with ``shutdown()`` and ``server_close()``.
        It answers GET and HEAD of the page's files (``/`` is ``index.html``) and 404
        for every other path. A client that disconnects early (broken pipe, reset,
        timeout) is not reported; any other error prints socketserver's traceback.
    """
    address = _loopback(host)
    _check_limits(port, timeout, max_connections)
    files = page_files(sky)
    table = {name: (content, _CONTENT_TYPES[Path(name).suffix]) for name, content in files.items()}
    handler = type("_PageHandler", (_Handler,), {"files": table, "csp": content_security_policy(files["index.html"]),
                                                 "timeout": float(timeout)})
    return _Server((address, port), handler, max_connections)


def serve(host: str = "127.0.0.1", port: int = 0, open_browser: bool = False, sky: SkySH | None = None) -> None:
    """
    Serve the page on loopback until Ctrl-C (``skysh view``).

    Parameters
    ----------
    host
        A loopback address; anything else is refused with a ValueError.
    port
        TCP port in [0, 65535]; 0 (default) picks a free one.
    open_browser
        Open the page in the default browser once the server listens.
    sky
        A loaded :class:`skysh.SkySH`; default the shipped coefficient file.

    Notes
    -----
    Prints ``skysh viewer: http://127.0.0.1:PORT/ (Ctrl-C to stop)`` once it
    listens and ``skysh viewer: stopped`` after Ctrl-C, then returns. The server is
    :func:`make_server`'s with its defaults (:data:`IDLE_TIMEOUT_S`, :data:`MAX_CONNECTIONS`).
    """
    if not isinstance(open_browser, bool):
        raise TypeError(f"open_browser must be True or False, got {open_browser!r}")
    server: http.server.ThreadingHTTPServer | None = None
    try:
        server = make_server(host, port, sky)  # a Ctrl-C while the page is generated also stops quietly
        address, bound = str(server.server_address[0]), int(server.server_address[1])
        url = f"http://[{address}]:{bound}/" if ":" in address else f"http://{address}:{bound}/"
        print(f"skysh viewer: {url} (Ctrl-C to stop)", flush=True)
        if open_browser:
            webbrowser.open(url)
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        if server is not None:
            server.server_close()
    print("skysh viewer: stopped", flush=True)
