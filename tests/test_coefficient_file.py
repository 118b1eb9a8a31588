"""
Tests of :mod:`skysh.coefficient_file`
======================================

Round trips (identical arrays and metadata) and every refusal the format
promises: wrong format string or version, truncated or corrupted bytes, files
that are not npz, missing entries, inconsistent shapes and non-finite tables.
Each refusal must be a :class:`~skysh.coefficient_file.CoefficientFileError`
(a ``ValueError``) whose message says what is wrong, from
:func:`~skysh.coefficient_file.read` and from :meth:`skysh.SkySH.load` alike.

Bad files are written here with plain ``np.savez`` (the package's writer
refuses to write them). No tolerances: a round trip must be bit-exact.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

from skysh import coefficient_file as cf
from skysh.runtime import SkySH

ENTRIES: tuple[str, ...] = ("format", "format_version", "table", "degrees", "metadata")


@pytest.fixture(scope="module")
def shipped_entries() -> dict[str, np.ndarray]:
    """The raw entries of the shipped file."""
    with np.load(cf.default_path(), allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def _small_table(bands: int = 3, degrees: tuple[int, int] = (4, 2), seed: int = 0) -> cf.SkyTable:
    rng = np.random.default_rng(seed)
    table = rng.normal(size=((degrees[0] + 1) * (degrees[1] + 1), bands * (bands + 1) // 2, 3))
    metadata = {"colourspace": "sRGB", "errors": {"by_bands": {"1": {"e_mean_worst": 1e-5}}}, "note": "ünïcode ✓",
                "nested": [1, 2.5, None, True]}
    return cf.SkyTable(table=table, degrees=np.tile(np.array(degrees, dtype=np.int64), (bands, 1)), metadata=metadata)


def _write_raw(path: Path, entries: dict[str, Any]) -> Path:
    with open(path, "wb") as handle:
        np.savez(handle, **entries)
    return path


def _save_npy(path: Path) -> None:
    with open(path, "wb") as handle:  # a handle keeps numpy from appending ".npy"
        np.save(handle, np.zeros(3))


def _refused(path: Path, match: str) -> None:
    """Both the reader and the runtime's loader refuse ``path`` with a CoefficientFileError matching ``match``."""
    with pytest.raises(cf.CoefficientFileError, match=match) as info:
        cf.read(path)
    assert isinstance(info.value, ValueError)
    with pytest.raises(cf.CoefficientFileError, match=match):
        SkySH.load(path)


class TestRoundTrip:
    def test_identical_arrays_and_metadata(self, tmp_path: Path) -> None:
        original = _small_table()
        path = cf.write(tmp_path / "sub" / "table.npz", original)  # creates the folder
        assert path == tmp_path / "sub" / "table.npz" and path.is_file()
        back = cf.read(path)
        np.testing.assert_array_equal(back.table, original.table)
        np.testing.assert_array_equal(back.degrees, original.degrees)
        assert back.table.dtype == np.float64 and back.degrees.dtype == np.int64
        assert back.metadata == original.metadata
        assert back.bands == 3 and back.max_degrees == (4, 2) and back.colourspace == "sRGB"

    def test_exact_path_without_npz_suffix(self, tmp_path: Path) -> None:
        path = cf.write(tmp_path / "table.bin", _small_table())
        assert path.is_file() and not (tmp_path / "table.bin.npz").exists()
        np.testing.assert_array_equal(cf.read(path).table, _small_table().table)

    def test_per_band_degrees(self, tmp_path: Path) -> None:
        degrees = np.array([[1, 0], [3, 2], [2, 1]], dtype=np.int64)
        table = np.zeros((4 * 3, 6, 3))
        table[0, :, :] = 1.0
        original = cf.SkyTable(table=table, degrees=degrees, metadata={})
        back = cf.read(cf.write(tmp_path / "t.npz", original))
        np.testing.assert_array_equal(back.degrees, degrees)
        assert back.max_degrees == (3, 2)

    def test_file_entries(self, tmp_path: Path) -> None:
        path = cf.write(tmp_path / "t.npz", _small_table())
        with np.load(path, allow_pickle=False) as data:  # no pickles needed
            assert set(data.files) == set(ENTRIES)
            assert str(data["format"]) == cf.FORMAT == "skysh-coefficients"
            assert int(data["format_version"]) == cf.FORMAT_VERSION == 1
            assert json.loads(str(data["metadata"])) == _small_table().metadata

    def test_read_table_is_read_only(self, tmp_path: Path) -> None:
        back = cf.read(cf.write(tmp_path / "t.npz", _small_table()))
        with pytest.raises(ValueError):
            back.table[0, 0, 0] = 1.0

    def test_shipped_file(self, shipped_entries: dict[str, np.ndarray], tmp_path: Path) -> None:
        sky = cf.read()
        assert sky.bands == 7 and sky.table.shape == (112, 28, 3)
        assert cf.read(cf.default_path()).metadata == sky.metadata
        # Rewriting the shipped tables reproduces them exactly.
        again = cf.read(cf.write(tmp_path / "copy.npz", sky))
        np.testing.assert_array_equal(again.table, sky.table)
        np.testing.assert_array_equal(again.degrees, sky.degrees)
        assert again.metadata == sky.metadata

    def test_default_path(self) -> None:
        path = cf.default_path()
        assert path.name == cf.DEFAULT_FILE_NAME and path.is_file()

    def test_zonal_half_layout(self) -> None:
        assert cf.zonal_half_layout(3) == [(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)]


class TestRefusals:
    @pytest.mark.parametrize("version", [0, 2, -1, 100])
    def test_wrong_format_version(self, tmp_path: Path, shipped_entries: dict, version: int) -> None:
        entries = dict(shipped_entries, format_version=np.array(version, dtype=np.int64))
        _refused(_write_raw(tmp_path / "v.npz", entries), rf"format version {version}.*reads version 1")

    @pytest.mark.parametrize(
        "version",
        [
            pytest.param(np.array("one")),
            pytest.param(np.array(1.5)),
        ],
        ids=["string", "fraction"],
    )
    def test_malformed_format_version(self, tmp_path: Path, shipped_entries: dict, version: np.ndarray) -> None:
        _refused(_write_raw(tmp_path / "v.npz", dict(shipped_entries, format_version=version)), "format version")

    @pytest.mark.parametrize("value", ["other", "skysh-coefficients-v2", ""])
    def test_wrong_format_string(self, tmp_path: Path, shipped_entries: dict, value: str) -> None:
        entries = dict(shipped_entries, format=np.array(value))
        _refused(_write_raw(tmp_path / "f.npz", entries), rf"has format '{value}', expected 'skysh-coefficients'")

    @pytest.mark.parametrize("fraction", [0.0, 0.001, 0.1, 0.5, 0.9, 0.999])
    def test_truncated(self, tmp_path: Path, fraction: float) -> None:
        raw = cf.default_path().read_bytes()
        path = tmp_path / "cut.npz"
        path.write_bytes(raw[: int(len(raw) * fraction)])
        _refused(path, r"not a readable coefficient file \(truncated or not an npz\)")

    def test_last_byte_cut(self, tmp_path: Path) -> None:
        raw = cf.default_path().read_bytes()
        path = tmp_path / "cut.npz"
        path.write_bytes(raw[:-1])
        _refused(path, "truncated")

    @pytest.mark.parametrize("damage", ["zeros", "gap"])
    def test_corrupted(self, tmp_path: Path, damage: str) -> None:
        raw = bytearray(cf.default_path().read_bytes())
        third = len(raw) // 3
        if damage == "zeros":
            raw[third : third + 64] = bytes(64)
        else:
            del raw[third : third + 100]
        path = tmp_path / "bad.npz"
        path.write_bytes(bytes(raw))
        _refused(path, "not a readable coefficient file")

    @pytest.mark.parametrize(
        "writer",
        [
            pytest.param(lambda p: p.write_text("hello, this is not an npz\n"), id="text"),
            pytest.param(lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200)), id="png-bytes"),
            pytest.param(lambda p: p.write_text(json.dumps({"format": "skysh-coefficients"})), id="json"),
            pytest.param(lambda p: _save_npy(p), id="npy"),
        ],
    )
    def test_not_an_npz(self, tmp_path: Path, writer: Callable[[Path], Any]) -> None:
        path = tmp_path / "not.npz"
        writer(path)
        _refused(path, "not a readable coefficient file|not an npz")

    def test_missing_file_and_directory(self, tmp_path: Path) -> None:
        _refused(tmp_path / "absent.npz", "not found")
        _refused(tmp_path, "not a readable coefficient file")

    def test_object_arrays_not_unpickled(self, tmp_path: Path, shipped_entries: dict) -> None:
        entries = dict(shipped_entries, table=np.array([None, 1], dtype=object))
        _refused(_write_raw(tmp_path / "o.npz", entries), "not a readable coefficient file")

    @pytest.mark.parametrize("missing", ENTRIES)
    def test_missing_entry(self, tmp_path: Path, shipped_entries: dict, missing: str) -> None:
        entries = {k: v for k, v in shipped_entries.items() if k != missing}
        _refused(_write_raw(tmp_path / "m.npz", entries), rf"lacks the entries \['{missing}'\]")

    def test_empty_npz(self, tmp_path: Path) -> None:
        _refused(_write_raw(tmp_path / "e.npz", {}), "lacks the entries")

    @pytest.mark.parametrize(
        "change, match",
        [
            (lambda e: {"table": e["table"][:-1]}, r"table must have shape \(112, 28, 3\).*got \(111, 28, 3\)"),
            (lambda e: {"table": e["table"][:, :-1]}, r"table must have shape \(112, 28, 3\).*got \(112, 27, 3\)"),
            (lambda e: {"table": e["table"][..., :2]}, r"table must have shape \(112, 28, 3\).*got \(112, 28, 2\)"),
            (lambda e: {"table": e["table"][0]}, r"table must have shape"),
            (lambda e: {"degrees": e["degrees"][:-1]}, r"table must have shape \(112, 21, 3\)"),
            (lambda e: {"degrees": e["degrees"][:, :1]}, r"degrees must have shape \(bands, 2\)"),
            (lambda e: {"degrees": e["degrees"].ravel()}, r"degrees must have shape \(bands, 2\)"),
            (lambda e: {"degrees": np.zeros((0, 2), dtype=np.int64)}, r"degrees must have shape \(bands, 2\) with 1 <= bands"),
            (lambda e: {"degrees": np.full((17, 2), 1, dtype=np.int64)}, r"1 <= bands <= 16"),
            (lambda e: {"degrees": np.where(np.arange(7)[:, None] == 0, -1, e["degrees"])}, "degrees must be non-negative"),
        ],
        ids=["terms", "rows", "channels", "ndim", "bands-vs-rows", "degree-columns", "degrees-1d", "no-bands",
             "too-many-bands", "negative-degree"],
    )
    def test_inconsistent_shapes(self, tmp_path: Path, shipped_entries: dict, change, match: str) -> None:
        _refused(_write_raw(tmp_path / "s.npz", dict(shipped_entries, **change(shipped_entries))), match)

    @pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
    def test_non_finite_table(self, tmp_path: Path, shipped_entries: dict, value: float) -> None:
        table = shipped_entries["table"].copy()
        table[5, 3, 1] = value
        _refused(_write_raw(tmp_path / "n.npz", dict(shipped_entries, table=table)), "table holds NaN or inf")

    def test_unreadable_metadata(self, tmp_path: Path, shipped_entries: dict) -> None:
        entries = dict(shipped_entries, metadata=np.array("{not json"))
        _refused(_write_raw(tmp_path / "j.npz", entries), "unreadable metadata")

    def test_metadata_not_an_object(self, tmp_path: Path, shipped_entries: dict) -> None:
        _refused(_write_raw(tmp_path / "j.npz", dict(shipped_entries, metadata=np.array("[1, 2]"))), "metadata")

    def test_non_numeric_table(self, tmp_path: Path, shipped_entries: dict) -> None:
        _refused(_write_raw(tmp_path / "t.npz", dict(shipped_entries, table=np.array("abc"))), "table")

    def test_terms_above_degrees_refused(self, tmp_path: Path, shipped_entries: dict) -> None:
        degrees = shipped_entries["degrees"].copy()
        degrees[0, 0] = 12
        _refused(_write_raw(tmp_path / "d.npz", dict(shipped_entries, degrees=degrees)), "degrees")


class TestWriteRefusals:
    def test_write_validates(self, tmp_path: Path) -> None:
        bad = _small_table()
        table = bad.table.copy()
        table[0, 0, 0] = np.nan
        with pytest.raises(cf.CoefficientFileError, match="NaN or inf"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=table, degrees=bad.degrees, metadata={}))
        with pytest.raises(cf.CoefficientFileError, match="table must have shape"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=bad.table[:-1], degrees=bad.degrees, metadata={}))
        assert not (tmp_path / "x.npz").exists()

    def test_runtime_constructor_validates(self) -> None:
        bad = _small_table()
        with pytest.raises(cf.CoefficientFileError, match="table must have shape"):
            SkySH(cf.SkyTable(table=bad.table[:, :-1], degrees=bad.degrees, metadata={}))
