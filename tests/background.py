"""
Background jobs of the tests
============================

Work a test module starts ahead so that its other tests overlap it (issue 14). A helper module (``from background
import ToolRuns``), not a test module; its fixture and hooks are in conftest. One core, :class:`Jobs` (each job run
once per key), used by :class:`Prefetched` (a module's jobs by name: :func:`prefetched`, :func:`start_early`,
:func:`server_session`) and :class:`ToolRuns` (compilers and shader validators on generated text: :data:`ToolJob`,
:data:`RUN_DIR`, :func:`glslang_job`). Jobs are queued ahead only when a module's tests all run in this process
(:func:`modules_stay_whole`; :func:`selected_names` and :func:`asked_for` tell which tests those are).

Jobs run subprocesses, or compute from fixed inputs (numpy releases the interpreter lock in its array loops);
they change nothing, read nothing that the module's tests change, and leave process-wide state alone (no import
that changes warning filters: warnings.catch_warnings is not thread-safe). A job's exception is raised in every
test that asks for its result, so each test fails for itself.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import threading
import urllib.request
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

import pytest

T = TypeVar("T")

WORKERS: int = max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
"""Threads of a :class:`Jobs` table by default (the session's :class:`ToolRuns`): one per core this process may use."""


# --------------------------------------------------------------------------- #
# The core, which tests run in this process, named jobs
# --------------------------------------------------------------------------- #
class Jobs(Generic[T]):
    """Jobs (functions of no arguments) run once per key, their result (or exception) given to every caller.

    :meth:`ahead` queues a job on ``workers`` threads, only if ``eager`` (False: pytest-xdist shares the module
    between processes, each of which then runs only what its own tests ask for); :meth:`run` waits for a job that
    is running or done, and runs a queued one (taken back from the queue) or a new one at once in the calling thread.
    """

    def __init__(self, eager: bool, workers: int = WORKERS) -> None:
        self.eager = eager
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="background")
        self._futures: dict[str, tuple[Future[T], Callable[[], T]]] = {}  # key -> its future, its job
        self._lock = threading.Lock()

    def ahead(self, key: str, job: Callable[[], T]) -> None:
        """Queue ``job`` as the job of ``key``, unless ``key`` is known or the table is not ``eager``."""
        with self._lock:
            if self.eager and key not in self._futures:
                self._futures[key] = self._pool.submit(job), job

    def run(self, key: str, job: Callable[[], T]) -> T:
        """The result of the job of ``key`` (the job queued for it, else ``job``), done once."""
        with self._lock:
            future, job = self._futures.get(key, (None, job))
            mine = future is None or future.cancel()  # new, or queued and taken back: run it in this thread
            if mine:
                future = Future()
                self._futures[key] = future, job
                future.set_running_or_notify_cancel()
        assert future is not None
        if mine:
            try:
                future.set_result(job())
            except BaseException as error:
                future.set_exception(error)
        return future.result()

    def close(self) -> None:
        """Drop the queued jobs and wait for those running (each has its own hang guard)."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def modules_stay_whole(config: pytest.Config) -> bool:
    """True when every test of a module runs in this process: no pytest-xdist, or ``--dist loadfile`` (the
    distribution mode conftest's ``pytest_configure_node`` passes on to each worker)."""
    workerinput = getattr(config, "workerinput", None)
    return workerinput is None or workerinput.get("skysh_dist") == "loadfile"


def selected_names(request: pytest.FixtureRequest) -> set[str]:
    """The names (function, without parameters, and class) of the selected tests of ``request``'s module: what a
    module's prefetch fixture queues the runs of."""
    items = [item for item in request.session.items if getattr(item, "module", None) is request.module]
    return ({getattr(item, "originalname", item.name) for item in items}
            | {cls.__name__ for cls in (getattr(item, "cls", None) for item in items) if cls is not None})


def asked_for(request: pytest.FixtureRequest, fixture: str) -> bool:
    """Whether a test of the requesting module selected in this session asks for ``fixture`` (directly or not)."""
    return any(getattr(item, "module", None) is request.module and fixture in getattr(item, "fixturenames", ())
               for item in request.session.items)


def start_early(request: pytest.FixtureRequest, *fixtures: str) -> None:
    """In a module's autouse fixture: set up the module fixtures ``fixtures`` now, at the module's first test, when
    the module stays in this process and a test of it selected in this session asks for one of them (so their
    background jobs overlap the module's other tests; a run of other tests of the module starts nothing)."""
    if modules_stay_whole(request.config):
        for name in fixtures:
            if asked_for(request, name):
                request.getfixturevalue(name)


class Prefetched(Jobs[T]):
    """Jobs by name (name -> function of no arguments), each started on its own thread when made (if ``eager``);
    :meth:`result` waits for one (or runs it, if it was not started)."""

    def __init__(self, jobs: Mapping[str, Callable[[], T]], eager: bool) -> None:
        super().__init__(eager, workers=max(1, len(jobs)))
        self.jobs = dict(jobs)
        for name, job in self.jobs.items():
            self.ahead(name, job)

    def result(self, name: str) -> T:
        """The return value of the job ``name``."""
        return self.run(name, self.jobs[name])


def prefetched(request: pytest.FixtureRequest, jobs: Mapping[str, Callable[[], T]]) -> Iterator[Prefetched[T]]:
    """Body of a module fixture (``yield from``): ``jobs`` as a :class:`Prefetched`, eager when the module stays in
    this process (:func:`modules_stay_whole`; True without pytest-xdist), closed at the module's end."""
    table = Prefetched(jobs, eager=modules_stay_whole(request.config))
    yield table
    table.close()


SERVER_START_TIMEOUT_S: float = 180.0
"""Hang guard of a server subprocess's start (imports, the coefficient file and colour-science on a shared
machine), and of each step after it."""


def _interruptible() -> None:
    """In the server's child before it starts: SIGINT back to its default, so Python turns it into Ctrl-C's
    KeyboardInterrupt even when the test run was started where SIGINT is ignored (a background job of a
    non-interactive shell inherits SIG_IGN, and Python then installs no handler)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def server_session(argv: list[str], cwd: Path) -> dict[str, Any]:
    """Run a server command (``python -m skysh view``, ``serve()``) in ``cwd``: the first line it prints, one GET of
    the loopback address in it (status and body), then Ctrl-C (SIGINT): its exit status, stdout and stderr. None
    (b"" for the body) where a step was not reached."""
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd,
                               preexec_fn=_interruptible if os.name == "posix" else None)
    timer = threading.Timer(SERVER_START_TIMEOUT_S, process.kill)
    timer.start()
    session: dict[str, Any] = {"line": "", "status": None, "body": b"", "code": None, "out": None, "err": None}
    try:
        session["line"] = process.stdout.readline() if process.stdout else ""
        address = re.search(r"http://127\.0\.0\.1:\d+/", session["line"])
        if address:
            with urllib.request.urlopen(address.group(0), timeout=SERVER_START_TIMEOUT_S) as response:
                session["status"], session["body"] = response.status, response.read()
            process.send_signal(signal.SIGINT)
            session["out"], session["err"] = process.communicate(timeout=SERVER_START_TIMEOUT_S)
            session["code"] = process.returncode
    finally:
        timer.cancel()
        if process.poll() is None:
            process.kill()
            process.communicate()
    return session


# --------------------------------------------------------------------------- #
# Tool runs
# --------------------------------------------------------------------------- #
TOOL_TIMEOUT_S: float = 300.0
"""Hang guard of one tool run (a compile or a validation takes well under a second normally)."""

RUN_DIR: str = "{dir}"
"""Placeholder in a :class:`ToolRuns` command for the run's own directory (where its files are written)."""

ToolJob = tuple[list[str], dict[str, str]]
"""A run for :class:`ToolRuns`: (argv with :data:`RUN_DIR` for its directory, files written there first)."""

GLSLANG: str | None = shutil.which("glslangValidator")
"""The Khronos reference shader compiler (Debian's ``glslang-tools``), or None: shader tests skip without it."""


def glslang_job(shader: str, language: str) -> ToolJob:
    """glslangValidator on a complete fragment shader: GLSL validated (its version is in its text), HLSL compiled to
    SPIR-V (entry point ``main``; glslang takes HLSL only with SPIR-V generation)."""
    assert GLSLANG is not None
    if language == "glsl":
        return [GLSLANG, f"{RUN_DIR}/sky.frag"], {"sky.frag": shader}
    return ([GLSLANG, "-D", "-V", "-e", "main", "-S", "frag", "-o", f"{RUN_DIR}/sky.spv", f"{RUN_DIR}/sky.hlsl"],
            {"sky.hlsl": shader})


@dataclass(frozen=True)
class ToolRun:
    """One finished tool run: its ``directory`` (the files written, and what the tool made) and its ``result``."""

    directory: Path
    result: subprocess.CompletedProcess


class ToolRuns:
    """Compilers and shader validators run on generated text, each distinct run once (a :class:`Jobs` table).

    A run is a command (``argv``, in which :data:`RUN_DIR` stands for the run's directory) and the files written
    there first (name -> text); its key is the sha256 of both, so identical builds (the same flags, header and
    harness) are made once and every test asking for them gets the same :class:`ToolRun`. :meth:`prefetch` queues
    runs ahead (a module's compiles overlap each other and its Python work); :meth:`run` waits for one or does it.
    Every directory is under ``base`` (in conftest's ``tool_runs`` fixture, the session's ``tmp_path_factory``:
    one per process, so xdist workers never share one).
    """

    def __init__(self, base: Path, eager: bool = True, workers: int = WORKERS) -> None:
        self.base = base
        self.jobs: Jobs[ToolRun] = Jobs(eager, workers)

    def _job(self, argv: Sequence[str], files: Mapping[str, str]) -> tuple[str, Callable[[], ToolRun]]:
        """A run's key and the job doing it."""
        key = hashlib.sha256(json.dumps([list(argv), sorted(files.items())]).encode()).hexdigest()
        return key, functools.partial(self._execute, self.base / key[:24], list(argv), dict(files))

    @staticmethod
    def _execute(directory: Path, argv: list[str], files: dict[str, str]) -> ToolRun:
        directory.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (directory / name).write_text(text)
        command = [arg.replace(RUN_DIR, str(directory)) for arg in argv]
        result = subprocess.run(command, capture_output=True, text=True, timeout=TOOL_TIMEOUT_S, check=False)
        return ToolRun(directory, result)

    def run(self, argv: Sequence[str], files: Mapping[str, str]) -> ToolRun:
        """The run of ``argv`` on ``files``: done once (here and now unless it is already going or done)."""
        return self.jobs.run(*self._job(argv, files))

    def prefetch(self, runs: Iterable[ToolJob]) -> None:
        """Queue ``runs`` ahead in order, each as soon as ``runs`` yields it (a generator's first runs start while it
        makes the next); nothing (``runs`` not even read) unless the table is eager.

        The GLSL validations of :func:`glslang_job` go last and together: one glslangValidator run over all their
        files (each file its own compilation unit, as glslang links only with -l or -V). If it passes, each counts
        as passed with its output; if not, each runs alone, so that a failure is told by its own run. HLSL compiles
        (-V links the files given together) go one by one.
        """
        if not self.jobs.eager:
            return
        glsl: dict[str, tuple[list[str], str, Callable[[], ToolRun]]] = {}  # key -> argv, shader, its own run
        for argv, files in runs:
            key, job = self._job(argv, files)
            if list(files) == ["sky.frag"]:
                glsl[key] = (list(argv), files["sky.frag"], job)
            else:
                self.jobs.ahead(key, job)
        if glsl:
            files = {f"s{k}.frag": shader for k, (_, shader, _) in enumerate(glsl.values())}
            batch: ToolJob = ([str(GLSLANG), *(f"{RUN_DIR}/{name}" for name in files)], files)
            self.jobs.ahead(*self._job(*batch))  # first: a member's thread then waits only for a batch already started
            for key, (argv, _, alone) in glsl.items():
                self.jobs.ahead(key, functools.partial(self._batched, batch, argv, alone))

    def _batched(self, batch: ToolJob, argv: list[str], alone: Callable[[], ToolRun]) -> ToolRun:
        """A member of ``batch``: the batch's run (waited for) if it passed, else the member's own run (``alone``)."""
        with contextlib.suppress(Exception):  # a batch that could not run at all: its members run alone as well
            done = self.run(*batch)
            if done.result.returncode == 0:
                return ToolRun(done.directory, subprocess.CompletedProcess(argv, 0, done.result.stdout, done.result.stderr))
        return alone()

    def close(self) -> None:
        """Drop the queued runs and wait for those running."""
        self.jobs.close()
