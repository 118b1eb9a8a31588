"""
Files skysh writes: whole or not at all, never its own
======================================================

-   :func:`package_dirs`: the folders of the installed package (its modules and its data).
-   :func:`check_output`: refuse an output path that is a directory or lies inside the package.
-   :func:`write_atomic`: write one file through a temporary file beside it and a rename.
-   :func:`write_together`: the same for several files, renamed only when all are written.

Every writer of skysh (the coefficient file, the PNG render, the exports, the
viewer's static page, the command line's ``--out``) goes through these, so that

-   a failed write (a full disk, a file-size limit, a signal) leaves the target
    as it was: the bytes go to ``.NAME.PID.THREAD.tmp`` beside the target, which
    is renamed over it only once complete, and removed on any failure;
-   a regular file the user names is replaced whole (as compilers do: a new
    inode, the umask's mode), and a symbolic link the user names is replaced by
    the file, never written through (``os.replace`` renames over the link itself);
-   the package's own files (the shipped coefficient file, its modules, the
    viewer's page) are never replaced by an output, unless a caller names the
    one file it may replace (``tools/fit_sky.py --force`` regenerating the
    shipped coefficient file).

The rename is atomic on POSIX file systems (``rename(2)``) and on Windows
(``MoveFileEx`` with replacement, which ``os.replace`` uses) when the temporary
file and the target share a folder, which they do by construction.
"""

from __future__ import annotations

import errno
import functools
import os
import threading
from collections.abc import Mapping
from pathlib import Path

__all__ = ["package_dirs", "check_output", "write_atomic", "write_together"]


@functools.cache
def package_dirs() -> tuple[Path, ...]:
    """
    The resolved folders whose files belong to skysh itself.

    Returns
    -------
    tuple of Path
        The ``skysh`` package folder, and the folder its ``skysh.data`` package
        is read from: ``skysh/data`` when installed, the checkout's ``data/``
        for an editable install (``pyproject.toml`` maps ``skysh.data`` there).
    """
    here = Path(__file__).resolve().parent
    checkout = here.parent
    if (checkout / "pyproject.toml").is_file() and (checkout / "data" / "__init__.py").is_file():
        return here, (checkout / "data").resolve()
    return (here,)


def check_output(path: str | os.PathLike[str], name: str = "path", may_replace: Path | None = None,
                 folder: bool = False) -> Path:
    """
    Refuse an output path that names a directory (or a file) or lies inside the package; return it as a Path.

    Parameters
    ----------
    path
        The file to write.
    name
        How the caller's user names the path, e.g. ``"--out"`` or ``"path"``: every refusal starts with it.
    may_replace
        One file of the package this caller may replace (the shipped coefficient file, for the
        fit tool's ``--force``), compared after resolving both; default none.
    folder
        The output is a folder to write files into (the viewer's page): an existing file there is
        refused instead of a directory.

    Returns
    -------
    Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    ValueError
        If ``path`` is empty, names an existing directory (with ``folder``: an existing non-directory), or lies inside
        :func:`package_dirs` (its folder resolved; a link as the last component is not followed, since
        it is replaced, not written through) other than ``may_replace``.
    TypeError
        If ``path`` is not a str or os.PathLike of text.
    """
    if not isinstance(path, (str, os.PathLike)) or isinstance(os.fspath(path), bytes):
        raise TypeError(f"{name} must be a str or os.PathLike naming a file as text, got {type(path).__name__}")
    out = Path(path)
    _check_kind(path, out, name, folder)
    # The folder resolved, the last component kept: a link named here is replaced, never followed (where it points
    # is not written).
    target = Path(os.path.realpath(out.parent)) / out.name
    if may_replace is None or target != Path(may_replace).resolve():
        _check_outside_package(target, out, name)
    return out


def _check_kind(path: str | os.PathLike[str], out: Path, name: str, folder: bool) -> None:
    """Refuse a ``path`` naming no file, or an existing directory (with ``folder``: an existing non-directory)."""
    if str(path) == "" or (not folder and out.name in ("", ".", "..")):
        raise ValueError(f"{name} {str(path)!r} names no file; give a file name")
    if folder and out.exists() and not out.is_dir():
        raise ValueError(f"{name} {out} is a file; give a folder")
    if not folder and out.is_dir():
        raise ValueError(f"{name} {out} is a directory; give a file name")


def _check_outside_package(target: Path, out: Path, name: str) -> None:
    """Refuse an output whose ``target`` (``out``, its folder resolved) lies inside :func:`package_dirs`."""
    for package in package_dirs():
        if target == package or package in target.parents:
            raise ValueError(f"{name} {out} lies inside skysh's own files ({package}); write somewhere else")


def write_together(files: Mapping[Path, bytes], parents: bool = False) -> list[Path]:
    """
    Write every file to a temporary file beside it, then rename each over its target.

    Nothing is renamed until every temporary file is complete; on a failure every temporary
    file is removed and no target has changed. (The renames themselves are one system call
    each; a failure between two of them, which needs the folder to vanish, would leave the
    first replaced.)

    Parameters
    ----------
    files
        Target path -> its bytes.
    parents
        Create the targets' missing folders; default False: a missing folder is an error (as a
        compiler's ``-o`` treats it), so a mistyped path creates nothing.

    Returns
    -------
    list of Path
        The targets, in order.

    Raises
    ------
    OSError
        If a file cannot be written, or a target is a directory (refused before anything is
        written); its ``filename`` is the target (not the temporary file).
    """
    for path in files:  # a rename over a directory would fail after others were renamed: refuse before writing
        if path.is_dir() and not path.is_symlink():
            raise IsADirectoryError(errno.EISDIR, "is a directory", str(path))
    written: list[tuple[Path, Path]] = []
    try:
        for path, data in files.items():
            if parents:
                path.parent.mkdir(parents=True, exist_ok=True)
            temporary = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
            written.append((temporary, path))
            try:
                with open(temporary, "xb") as handle:  # exclusive; mode from the umask
                    handle.write(data)
            except OSError as error:
                raise OSError(error.errno, error.strerror, str(path)) from None
        for temporary, path in written:
            os.replace(temporary, path)
    finally:
        for temporary, _ in written:
            if temporary.exists():
                temporary.unlink()
    return list(files)


def write_atomic(path: str | os.PathLike[str], data: bytes, parents: bool = False) -> Path:
    """
    Write ``data`` to ``path`` through a temporary file beside it and a rename: never half written.

    Parameters
    ----------
    path
        The file to write. A symbolic link there is replaced by the file, never written through.
    data
        The file's bytes.
    parents
        Create the missing folders of ``path`` (default False, as :func:`write_together`).

    Returns
    -------
    Path
        ``path`` as a Path.

    Raises
    ------
    OSError
        If the file cannot be written; the target is then as it was.
    """
    return write_together({Path(path): data}, parents)[0]
