"""
Tests of the files skysh writes (skysh.files) and of every ``--out`` of the command line
======================================================================================

-   :func:`skysh.files.check_output` refuses a directory, an empty name and anything inside
    the package (the shipped coefficient file, a module, the viewer's page), allows the one
    file a caller names (the fit tool's ``--force``), and never follows a link in the last
    component (the link is replaced, so where it points is not written).
-   :func:`skysh.files.write_together` leaves every target as it was when a write fails part
    way (a real file-size limit, ``RLIMIT_FSIZE``, in a subprocess), leaves no temporary file
    behind, replaces a symbolic link instead of writing through it, and creates no folder
    unless asked.
-   The command line: ``export``, ``render`` and ``view --out`` each refuse the shipped file,
    a package file and a directory (a file for ``view``) with exit 2 and one line naming
    ``--out``, before any work; a failed write exits 2 naming ``--out`` with the target intact.
    The shipped coefficient file is byte-identical after every case (checked by hash).

The file-size limit is real (``resource.setrlimit`` in the child, POSIX only): Python ignores
SIGXFSZ, so the write fails with EFBIG as a full disk would fail with ENOSPC.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from skysh import files
from skysh.app import cli
from skysh.table import coefficient_file

ROOT = Path(__file__).resolve().parent.parent

SUBPROCESS_TIMEOUT_S: float = 180.0
"""Hang guard of each subprocess (imports and the coefficient file on a shared machine)."""

SIZE_LIMIT_BYTES: int = 64 * 1024
"""The child's file-size limit: below every export (the C header is about 120 KiB) and the PNG of
a default render, above nothing that matters; what the issue measured partial files at."""

SUN = ["--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3"]

OLD: bytes = b"the user's old file\n"
"""What a target holds before a refused or failed write: it must still hold exactly this."""


def shipped_digest() -> str:
    return hashlib.sha256(coefficient_file.default_path().read_bytes()).hexdigest()


@pytest.fixture(scope="module", autouse=True)
def shipped_file_untouched() -> object:
    """Every test of this module leaves the shipped coefficient file byte-identical."""
    before = shipped_digest()
    yield
    assert shipped_digest() == before


def run_cli(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = cli.main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def run_limited(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``python -m skysh argv`` with a file-size limit of :data:`SIZE_LIMIT_BYTES`."""
    code = (f"import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, ({SIZE_LIMIT_BYTES}, {SIZE_LIMIT_BYTES}))\n"
            "from skysh.app.cli import main; sys.exit(main(sys.argv[1:]))")
    return subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=cwd,
                          timeout=SUBPROCESS_TIMEOUT_S, check=False)


def leftovers(folder: Path) -> list[str]:
    """Temporary files the writers left in ``folder`` (there must be none)."""
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


# --------------------------------------------------------------------------- #
# skysh.files
# --------------------------------------------------------------------------- #
class TestCheckOutput:
    def test_package_files_are_refused(self) -> None:
        for path in (coefficient_file.default_path(), Path(files.__file__), Path(files.__file__).parent / "web" / "x.js"):
            with pytest.raises(ValueError, match=r"^--out .* lies inside skysh's own files"):
                files.check_output(path, "--out")

    def test_the_named_file_may_be_replaced(self) -> None:
        """The fit tool's --force: the shipped file, and only it."""
        shipped = coefficient_file.default_path()
        assert files.check_output(shipped, "--out", may_replace=shipped) == shipped
        with pytest.raises(ValueError, match="lies inside"):
            files.check_output(shipped.with_name("other.npz"), "--out", may_replace=shipped)

    def test_directories_and_empty_names_are_refused(self, tmp_path: Path) -> None:
        with pytest.raises(ValueError, match=r"^--out .* is a directory; give a file name"):
            files.check_output(tmp_path, "--out")
        with pytest.raises(ValueError, match="names no file"):
            files.check_output("", "--out")
        (tmp_path / "f").write_bytes(OLD)
        with pytest.raises(ValueError, match=r"is a file; give a folder"):
            files.check_output(tmp_path / "f", "--out", folder=True)
        assert files.check_output(tmp_path, "--out", folder=True) == tmp_path

    def test_not_a_path_is_a_type_error(self) -> None:
        for bad in (b"x", 0, None):
            with pytest.raises(TypeError, match=r"^path must be a str or os\.PathLike"):
                files.check_output(bad)  # type: ignore[arg-type]

    def test_a_link_into_the_package_is_not_followed(self, tmp_path: Path) -> None:
        """The link is replaced by the output, so the package file it points at is not at stake."""
        link = tmp_path / "link.npz"
        link.symlink_to(coefficient_file.default_path())
        assert files.check_output(link, "--out") == link

    def test_a_folder_linked_into_the_package_is_followed(self, tmp_path: Path) -> None:
        """Negative control of the above: a link in the folder part is resolved, and refused."""
        linked = tmp_path / "pkg"
        linked.symlink_to(Path(files.__file__).parent)
        with pytest.raises(ValueError, match="lies inside"):
            files.check_output(linked / "new.h", "--out")


class TestWrite:
    def test_replaces_a_link_never_writes_through_it(self, tmp_path: Path) -> None:
        target, link = tmp_path / "target", tmp_path / "link"
        target.write_bytes(OLD)
        link.symlink_to(target)
        files.write_atomic(link, b"new")
        assert target.read_bytes() == OLD and not link.is_symlink() and link.read_bytes() == b"new"

    def test_a_missing_folder_is_an_error_unless_asked(self, tmp_path: Path) -> None:
        with pytest.raises(FileNotFoundError):
            files.write_atomic(tmp_path / "missing" / "f", b"x")
        assert not (tmp_path / "missing").exists()
        files.write_atomic(tmp_path / "made" / "f", b"x", parents=True)
        assert (tmp_path / "made" / "f").read_bytes() == b"x"

    def test_all_or_nothing(self, tmp_path: Path) -> None:
        """The second file cannot be written (its folder is missing; then a directory stands there): the first
        is not replaced."""
        first, second = tmp_path / "first", tmp_path / "second"
        first.write_bytes(OLD)
        second.mkdir()
        for bad in (tmp_path / "missing" / "second", second):
            with pytest.raises(OSError) as caught:
                files.write_together({first: b"new", bad: b"new"})
            assert first.read_bytes() == OLD and leftovers(tmp_path) == []
            assert caught.value.filename == str(bad)

    def test_a_failed_write_leaves_the_target(self, tmp_path: Path) -> None:
        """A real file-size limit in a child: EFBIG part way, the target intact, no temporary file."""
        target = tmp_path / "big"
        target.write_bytes(OLD)
        code = (f"import resource; resource.setrlimit(resource.RLIMIT_FSIZE, ({SIZE_LIMIT_BYTES}, {SIZE_LIMIT_BYTES}))\n"
                "from skysh import files\n"
                "try:\n    files.write_atomic('big', bytes(1 << 20))\nexcept OSError as e:\n    print(e.errno, e.filename)")
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                              timeout=SUBPROCESS_TIMEOUT_S, check=False)
        assert done.returncode == 0 and done.stdout.split() == [str(__import__("errno").EFBIG), "big"], done
        assert target.read_bytes() == OLD and leftovers(tmp_path) == []


# --------------------------------------------------------------------------- #
# The command line's --out
# --------------------------------------------------------------------------- #
WRITERS: dict[str, list[str]] = {
    "export c": ["export", "--format", "c", "--out"],
    "export js": ["export", "--format", "js", "--out"],
    "render": ["render", *SUN, "--out"],
}
"""Commands that write one named file with ``--out`` (the flag last: the path follows)."""


class TestCommandLineOut:
    @pytest.mark.parametrize("command", WRITERS)
    def test_package_files_are_refused(self, command: str, capsys: pytest.CaptureFixture) -> None:
        for path in (coefficient_file.default_path(), Path(cli.__file__)):
            before = path.read_bytes()
            code, out, err = run_cli([*WRITERS[command], str(path)], capsys)
            assert code == 2 and out == "" and err.startswith(f"skysh: error: --out {path} lies inside") and \
                err.count("\n") == 1, err
            assert path.read_bytes() == before

    @pytest.mark.parametrize("command", WRITERS)
    def test_a_directory_is_refused(self, command: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run_cli([*WRITERS[command], str(tmp_path)], capsys)
        assert code == 2 and err.startswith(f"skysh: error: --out {tmp_path} is a directory"), err

    @pytest.mark.parametrize("command", WRITERS)
    def test_a_link_is_replaced(self, command: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        target, link = tmp_path / "target", tmp_path / "out.x"
        target.write_bytes(OLD)
        link.symlink_to(target)
        code, _, err = run_cli([*WRITERS[command], str(link)], capsys)
        assert code == 0, err
        assert target.read_bytes() == OLD and not link.is_symlink() and link.stat().st_size > len(OLD)

    @pytest.mark.parametrize("command", WRITERS)
    def test_a_regular_file_is_replaced_whole(self, command: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        target = tmp_path / "out.x"
        target.write_bytes(OLD * 100_000)  # longer than any output: a write in place would leave its tail
        code, _, err = run_cli([*WRITERS[command], str(target)], capsys)
        assert code == 0, err
        assert OLD not in target.read_bytes() and leftovers(tmp_path) == []

    @pytest.mark.parametrize("command", WRITERS)
    def test_a_failed_write_leaves_the_target(self, command: str, tmp_path: Path) -> None:
        target = tmp_path / "out.x"
        target.write_bytes(OLD)
        done = run_limited([*WRITERS[command], "out.x"], tmp_path)
        assert done.returncode == 2 and done.stdout == "", done
        assert done.stderr.startswith("skysh: error: --out out.x: cannot write: File too large") and \
            done.stderr.count("\n") == 1, done.stderr
        assert target.read_bytes() == OLD and sorted(p.name for p in tmp_path.iterdir()) == ["out.x"]  # js: neither file

    def test_a_missing_folder_is_not_created(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run_cli([*WRITERS["export c"], str(tmp_path / "missing" / "sky.h")], capsys)
        assert code == 2 and "--out" in err and not (tmp_path / "missing").exists(), err

    def test_standard_output_is_still_accepted(self, capsys: pytest.CaptureFixture) -> None:
        code, out, _ = run_cli(["export", "--format", "json", "--out", "-"], capsys)
        assert code == 0 and out.lstrip().startswith("{")


class TestViewOut:
    def test_package_folder_and_a_file_are_refused(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        web = Path(cli.__file__).parent / "web"
        before = {p.name: p.read_bytes() for p in web.iterdir()}
        code, _, err = run_cli(["view", "--out", str(web)], capsys)
        assert code == 2 and err.startswith(f"skysh: error: --out {web} lies inside skysh's own files"), err
        assert {p.name: p.read_bytes() for p in web.iterdir()} == before
        (tmp_path / "file").write_bytes(OLD)
        code, _, err = run_cli(["view", "--out", str(tmp_path / "file")], capsys)
        assert code == 2 and err.startswith(f"skysh: error: --out {tmp_path / 'file'} is a file"), err

    def test_a_failed_write_leaves_the_page(self, tmp_path: Path) -> None:
        page = tmp_path / "page"
        page.mkdir()
        (page / "index.html").write_bytes(OLD)
        done = run_limited(["view", "--out", "page"], tmp_path)
        assert done.returncode == 2 and done.stderr.startswith("skysh: error: --out page: cannot write") and \
            done.stderr.count("\n") == 1, done.stderr
        assert sorted(p.name for p in page.iterdir()) == ["index.html"] and (page / "index.html").read_bytes() == OLD

    def test_a_link_in_the_folder_is_replaced(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        target = tmp_path / "target"
        target.write_bytes(OLD)
        page = tmp_path / "page"
        page.mkdir()
        (page / "index.html").symlink_to(target)
        code, _, err = run_cli(["view", "--out", str(page)], capsys)
        assert code == 0, err
        assert target.read_bytes() == OLD and not (page / "index.html").is_symlink()


@pytest.mark.skipif(os.name != "posix", reason="RLIMIT_FSIZE is POSIX")
def test_limit_is_below_every_output(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """The failed-write tests above prove something only if each output is larger than the limit."""
    for command, argv in WRITERS.items():
        path = tmp_path / f"{command.replace(' ', '_')}.out"
        assert cli.main([*argv, str(path)]) == 0
        assert path.stat().st_size > SIZE_LIMIT_BYTES, command
    capsys.readouterr()
