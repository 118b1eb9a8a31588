"""
Tests of :mod:`skysh.coefficient_file`
======================================

The format (version 2) and its writer: round trips (identical arrays,
metadata as stored), byte-for-byte determinism, members read by independent
readers (:mod:`zipfile`, :func:`numpy.load`, :mod:`numpy.lib.format`), the
content hash recomputed here from its documented definition with
:mod:`hashlib`, the bounds (a file at every bound is accepted), the colourspace
list checked against colour-science, and the ordinary refusals of the reader
and the writer. Hostile and corrupted files are in tests/test_corrupt_file.py.

Files that the package's writer refuses to write are made here with
:func:`numpy.savez` (an independent writer). No tolerances: a round trip must
be bit-exact.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

from skysh import coefficient_file as cf
from skysh import poly
from skysh.runtime import SkySH

ENTRIES: tuple[str, ...] = ("format", "format_version", "table", "degrees", "metadata")


def _canonical(value: Any) -> bytes:
    """Canonical JSON as the module docstring defines it, typed here."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode("ascii")


@pytest.fixture(scope="module")
def shipped_entries() -> dict[str, np.ndarray]:
    """The raw entries of the shipped file (numpy's own reader)."""
    with np.load(cf.default_path(), allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def _small_table(bands: int = 3, degrees: tuple[int, int] = (4, 2), seed: int = 0) -> cf.SkyTable:
    rng = np.random.default_rng(seed)
    table = rng.normal(size=((degrees[0] + 1) * (degrees[1] + 1), bands * (bands + 1) // 2, 3))
    metadata = {"colourspace": "sRGB", "errors": {"by_bands": {"1": {"e_mean_worst": 1e-5}}}, "note": "ünïcode ✓",
                "nested": [1, 2.5, None, True]}
    return cf.SkyTable(table=table, degrees=np.tile(np.array(degrees, dtype=np.int64), (bands, 1)), metadata=metadata)


def _write_raw(path: Path, entries: dict[str, Any], compressed: bool = False) -> Path:
    with open(path, "wb") as handle:  # a handle keeps numpy from appending ".npz"
        (np.savez_compressed if compressed else np.savez)(handle, **entries)
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


def _rehashed(entries: dict[str, np.ndarray], **metadata_changes: Any) -> dict[str, np.ndarray]:
    """Entries whose metadata is changed and whose hash is then made consistent (a hostile but careful writer)."""
    metadata = json.loads(bytes(entries["metadata"]).decode("ascii"))
    metadata.update(metadata_changes)
    metadata[cf.HASH_KEY] = cf.content_sha256(entries["table"], entries["degrees"], metadata)
    return dict(entries, metadata=np.frombuffer(_canonical(metadata), dtype=np.uint8))


class TestRoundTrip:
    def test_identical_arrays_and_metadata(self, tmp_path: Path) -> None:
        original = _small_table()
        path = cf.write(tmp_path / "sub" / "table.npz", original)  # creates the folder
        assert path == tmp_path / "sub" / "table.npz" and path.is_file()
        back = cf.read(path)
        np.testing.assert_array_equal(back.table, original.table)
        np.testing.assert_array_equal(back.degrees, original.degrees)
        assert back.table.dtype == np.float64 and back.degrees.dtype == np.int64
        # Stored: the caller's metadata plus the runtime fields and the hash.
        added = {"domain": cf.DOMAIN, "basis": cf.BASIS, "term_order": cf.TERM_ORDER, "degrees": [[4, 2]] * 3, "bands": 3}
        assert back.metadata == {**original.metadata, **added, cf.HASH_KEY: back.metadata[cf.HASH_KEY]}
        assert back.bands == 3 and back.max_degrees == (4, 2) and back.colourspace == "sRGB"
        assert list(tmp_path.joinpath("sub").iterdir()) == [path]  # no temporary file left

    def test_exact_path_without_npz_suffix(self, tmp_path: Path) -> None:
        path = cf.write(tmp_path / "table.bin", _small_table())
        assert path.is_file() and not (tmp_path / "table.bin.npz").exists()
        np.testing.assert_array_equal(cf.read(path).table, _small_table().table)

    def test_per_band_degrees(self, tmp_path: Path) -> None:
        degrees = np.array([[1, 0], [3, 2], [2, 1]], dtype=np.int64)
        table = np.zeros((4 * 3, 6, 3))
        table[0, :, :] = 1.0
        back = cf.read(cf.write(tmp_path / "t.npz", cf.SkyTable(table=table, degrees=degrees, metadata={})))
        np.testing.assert_array_equal(back.degrees, degrees)
        assert back.max_degrees == (3, 2) and back.colourspace == "sRGB"

    def test_members_read_by_independent_readers(self, tmp_path: Path) -> None:
        path = cf.write(tmp_path / "t.npz", _small_table())
        with zipfile.ZipFile(path) as archive:
            infos = archive.infolist()
            assert [i.filename for i in infos] == list(cf.MEMBERS)
            assert all(i.compress_type == zipfile.ZIP_STORED for i in infos)
            assert archive.testzip() is None  # every CRC-32 right
        with np.load(path, allow_pickle=False) as data:  # no pickles needed
            assert data.files == list(ENTRIES)
            assert str(data["format"]) == cf.FORMAT == "skysh-coefficients"
            assert data["format_version"].dtype == np.int64 and int(data["format_version"]) == cf.FORMAT_VERSION == 2
            assert data["table"].dtype == np.float64 and data["table"].shape == (15, 6, 3)
            raw = bytes(data["metadata"])
        metadata = json.loads(raw.decode("ascii"))
        assert metadata == cf.read(path).metadata and raw == _canonical(metadata)  # canonical JSON, as documented

    def test_deterministic_bytes(self, tmp_path: Path) -> None:
        a = cf.write(tmp_path / "a.npz", _small_table()).read_bytes()
        b = cf.write(tmp_path / "b.npz", _small_table()).read_bytes()
        assert a == b
        assert cf.write(tmp_path / "a.npz", cf.read(tmp_path / "a.npz")).read_bytes() == a  # rewrite of a read table

    def test_content_hash_definition(self, tmp_path: Path) -> None:
        back = cf.read(cf.write(tmp_path / "t.npz", _small_table()))
        digest = hashlib.sha256(b"skysh-coefficients\n2\n")
        digest.update(f"table <f8 [15, 6, 3] {15 * 6 * 3 * 8}\n".encode())
        digest.update(back.table.astype("<f8").tobytes())
        digest.update(f"degrees <i8 [3, 2] {3 * 2 * 8}\n".encode())
        digest.update(back.degrees.astype("<i8").tobytes())
        text = _canonical({k: v for k, v in back.metadata.items() if k != cf.HASH_KEY})
        digest.update(f"metadata {len(text)}\n".encode() + text)
        assert back.metadata[cf.HASH_KEY] == digest.hexdigest()
        # Negative control: the hash moves with any number and any metadata field.
        changed = back.table.copy()
        changed[0, 0, 0] = np.nextafter(changed[0, 0, 0], np.inf)
        assert cf.content_sha256(changed, back.degrees, back.metadata) != digest.hexdigest()
        assert cf.content_sha256(back.table, back.degrees, dict(back.metadata, colourspace="ACEScg")) != digest.hexdigest()

    def test_read_arrays_are_read_only(self, tmp_path: Path) -> None:
        back = cf.read(cf.write(tmp_path / "t.npz", _small_table()))
        with pytest.raises(ValueError):
            back.table[0, 0, 0] = 1.0
        with pytest.raises(ValueError):
            back.degrees[0, 0] = 1

    def test_shipped_file(self, tmp_path: Path) -> None:
        sky = cf.read()
        assert sky.bands == 7 and sky.table.shape == (112, 28, 3) and sky.colourspace == "sRGB"
        assert cf.read(cf.default_path()).metadata == sky.metadata
        # Rewriting the shipped tables reproduces the shipped file byte for byte.
        assert cf.write(tmp_path / "copy.npz", sky).read_bytes() == cf.default_path().read_bytes()

    def test_default_path(self) -> None:
        path = cf.default_path()
        assert path.name == cf.DEFAULT_FILE_NAME and path.is_file()

    def test_zonal_half_layout(self) -> None:
        assert cf.zonal_half_layout(3) == [(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)]


class TestBounds:
    def test_member_bounds_follow_from_the_format(self) -> None:
        rows = cf.MAX_FILE_BANDS * (cf.MAX_FILE_BANDS + 1) // 2
        assert cf.MAX_MEMBER_BYTES["table.npy"] - 256 == (cf.MAX_FILE_DEGREE + 1) ** 2 * rows * 3 * 8
        assert cf.MAX_FILE_BYTES < 1 << 20  # "a hostile file costs a few megabytes"

    def test_largest_file_is_accepted(self, tmp_path: Path) -> None:
        """Every bound at once (bands, degrees, metadata): written, within MAX_FILE_BYTES, read back."""
        bands, top = cf.MAX_FILE_BANDS, cf.MAX_FILE_DEGREE
        table = np.random.default_rng(3).uniform(-cf.MAX_TABLE_MAGNITUDE, cf.MAX_TABLE_MAGNITUDE,
                                                 ((top + 1) ** 2, bands * (bands + 1) // 2, 3))
        metadata = {"colourspace": "ACES2065-1", "padding": "x" * (cf.MAX_METADATA_BYTES - 2000)}
        path = cf.write(tmp_path / "big.npz", cf.SkyTable(table, np.full((bands, 2), top, dtype=np.int64), metadata))
        assert cf.MAX_FILE_BYTES - 4096 < path.stat().st_size <= cf.MAX_FILE_BYTES
        np.testing.assert_array_equal(cf.read(path).table, table)

    def test_file_colourspaces_exist_in_colour_science(self) -> None:
        import colour

        for name in cf.FILE_COLOURSPACES:
            assert name in colour.RGB_COLOURSPACES, name
        assert "Not A Colourspace" not in colour.RGB_COLOURSPACES  # negative control of the membership test

    def test_domain_is_the_packages(self) -> None:
        assert cf.DOMAIN == {"sun_zenith": [0.0, np.pi / 2], "turbidity": [2.5, 6.0]}
        assert tuple(cf.DOMAIN["sun_zenith"]) == poly.SUN_ZENITH_DOMAIN


class TestRefusals:
    def test_version_1_names_the_versions(self, tmp_path: Path, shipped_entries: dict) -> None:
        # Version 1 as skysh 0.1.0 wrote it: savez_compressed, metadata a '<U' string, no hash.
        metadata = json.loads(bytes(shipped_entries["metadata"]).decode("ascii"))
        metadata.pop(cf.HASH_KEY)
        entries = dict(shipped_entries, format_version=np.array(1, dtype=np.int64), metadata=np.array(json.dumps(metadata)))
        _refused(_write_raw(tmp_path / "v1.npz", entries, compressed=True),
                 r"format version 1 is no longer read: this skysh \(.*\) reads format version 2 only.*skysh fit --out")

    @pytest.mark.parametrize("version", [0, 3, -1, 100])
    def test_wrong_format_version(self, tmp_path: Path, shipped_entries: dict, version: int) -> None:
        entries = dict(shipped_entries, format_version=np.array(version, dtype=np.int64))
        _refused(_write_raw(tmp_path / "v.npz", entries), rf"has format version {version}; .* reads format version 2 only")

    @pytest.mark.parametrize("version", [np.array("one"), np.array(1.5), np.array(True)], ids=["string", "fraction", "bool"])
    def test_malformed_format_version(self, tmp_path: Path, shipped_entries: dict, version: np.ndarray) -> None:
        _refused(_write_raw(tmp_path / "v.npz", dict(shipped_entries, format_version=version)), "malformed format version")

    @pytest.mark.parametrize("value", ["other", "skysh-coefficients-v2", ""])
    def test_wrong_format_string(self, tmp_path: Path, shipped_entries: dict, value: str) -> None:
        entries = dict(shipped_entries, format=np.array(value))
        _refused(_write_raw(tmp_path / "f.npz", entries), rf"has format '{value}', expected 'skysh-coefficients'")

    def test_compressed_members(self, tmp_path: Path, shipped_entries: dict) -> None:
        _refused(_write_raw(tmp_path / "c.npz", shipped_entries, compressed=True), "compressed; format version 2 stores")

    def test_same_content_other_writer(self, tmp_path: Path, shipped_entries: dict) -> None:
        """numpy's own writer, the same content: refused by the byte-for-byte comparison."""
        _refused(_write_raw(tmp_path / "n.npz", shipped_entries), "differs from what skysh writes for its content")

    @pytest.mark.parametrize(
        "writer",
        [
            pytest.param(lambda p: p.write_text("hello, this is not an npz\n"), id="text"),
            pytest.param(lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200)), id="png-bytes"),
            pytest.param(lambda p: p.write_text(json.dumps({"format": "skysh-coefficients"})), id="json"),
            pytest.param(lambda p: _save_npy(p), id="npy"),
            pytest.param(lambda p: p.write_bytes(b""), id="empty"),
        ],
    )
    def test_not_an_npz(self, tmp_path: Path, writer: Callable[[Path], Any]) -> None:
        path = tmp_path / "not.npz"
        writer(path)
        _refused(path, r"not a readable coefficient file \(truncated or not an npz\)")

    def test_missing_file_and_directory(self, tmp_path: Path) -> None:
        _refused(tmp_path / "absent.npz", "not found")
        _refused(tmp_path, "is a directory, not a regular file")

    @pytest.mark.parametrize("path", [3, None.__class__, b"/tmp/x.npz"], ids=["int", "type", "bytes"])
    def test_path_type(self, path: Any) -> None:
        with pytest.raises(cf.CoefficientFileError, match="path must be a str or os.PathLike"):
            cf.read(path)

    def test_object_arrays_not_unpickled(self, tmp_path: Path, shipped_entries: dict) -> None:
        entries = dict(shipped_entries, table=np.array([None, 1], dtype=object))
        with open(tmp_path / "o.npz", "wb") as handle:
            np.savez(handle, **entries)  # numpy pickles the object array; the reader never unpickles
        _refused(tmp_path / "o.npz", "table.npy holds object values")

    @pytest.mark.parametrize("missing", ENTRIES)
    def test_missing_entry(self, tmp_path: Path, shipped_entries: dict, missing: str) -> None:
        entries = {k: v for k, v in shipped_entries.items() if k != missing}
        _refused(_write_raw(tmp_path / "m.npz", entries), rf"lacks the members \['{missing}.npy'\]")

    def test_empty_npz(self, tmp_path: Path) -> None:
        _refused(_write_raw(tmp_path / "e.npz", {}), "lacks the members")

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
            (lambda e: {"degrees": np.full((8, 2), 1, dtype=np.int64)}, r"1 <= bands <= 7"),
            (lambda e: {"degrees": np.where(np.arange(7)[:, None] == 0, -1, e["degrees"])}, r"degrees must lie in \[0, 31\]"),
            (lambda e: {"degrees": np.full((7, 2), 32, dtype=np.int64)}, r"degrees must lie in \[0, 31\]"),
        ],
        ids=["terms", "rows", "channels", "ndim", "bands-vs-rows", "degree-columns", "degrees-1d", "no-bands",
             "too-many-bands", "negative-degree", "degree-too-high"],
    )
    def test_inconsistent_shapes(self, tmp_path: Path, shipped_entries: dict, change, match: str) -> None:
        _refused(_write_raw(tmp_path / "s.npz", dict(shipped_entries, **change(shipped_entries))), match)

    @pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
    def test_non_finite_table(self, tmp_path: Path, shipped_entries: dict, value: float) -> None:
        table = shipped_entries["table"].copy()
        table[5, 3, 1] = value
        _refused(_write_raw(tmp_path / "n.npz", dict(shipped_entries, table=table)), "table holds NaN or inf")

    @pytest.mark.parametrize(
        "text, match",
        [
            ("{not json", "unreadable metadata"),
            ("[1, 2]", "not a JSON object"),
            ('{"a": NaN}', "not in canonical form"),
            ('{"b": 1, "a": 2}', "not in canonical form"),
            ('{"a": 1, "a": 2}', "not in canonical form"),
            ('{"a":1}', "lacks the fields"),
            ("{\"\u00e9\": 1}", "unreadable metadata"),
        ],
        ids=["not-json", "array", "nan", "unsorted", "duplicate-key", "no-runtime-fields", "not-ascii"],
    )
    def test_bad_metadata(self, tmp_path: Path, shipped_entries: dict, text: str, match: str) -> None:
        entries = dict(shipped_entries, metadata=np.frombuffer(text.encode("utf-8"), dtype=np.uint8))
        _refused(_write_raw(tmp_path / "j.npz", entries), match)

    def test_string_metadata_refused(self, tmp_path: Path, shipped_entries: dict) -> None:
        entries = dict(shipped_entries, metadata=np.array(bytes(shipped_entries["metadata"]).decode("ascii")))
        _refused(_write_raw(tmp_path / "j.npz", entries), r"metadata.npy holds .* the format stores '\|u1'")

    def test_non_numeric_table(self, tmp_path: Path, shipped_entries: dict) -> None:
        _refused(_write_raw(tmp_path / "t.npz", dict(shipped_entries, table=np.array("abc"))), "table.npy holds")

    def test_terms_above_degrees_refused(self, tmp_path: Path, shipped_entries: dict) -> None:
        degrees = shipped_entries["degrees"].copy()
        degrees[0, 0] = 12
        entries = _rehashed(dict(shipped_entries, degrees=degrees), degrees=degrees.tolist())
        _refused(_write_raw(tmp_path / "d.npz", entries), "non-zero terms above the degrees")


class TestWriteRefusals:
    def test_write_validates(self, tmp_path: Path) -> None:
        bad = _small_table()
        table = bad.table.copy()
        table[0, 0, 0] = np.nan
        with pytest.raises(cf.CoefficientFileError, match="NaN or inf"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=table, degrees=bad.degrees, metadata={}))
        with pytest.raises(cf.CoefficientFileError, match="table must have shape"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=bad.table[:-1], degrees=bad.degrees, metadata={}))
        with pytest.raises(cf.CoefficientFileError, match=r"\|value\| 1e\+05, above 10000"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=bad.table * 0 + 1e5, degrees=bad.degrees, metadata={}))
        assert not (tmp_path / "x.npz").exists()

    @pytest.mark.parametrize(
        "metadata, match",
        [
            ({"colourspace": "Bogus RGB"}, "colourspace 'Bogus RGB' is not one a coefficient file may use"),
            ({"colourspace": 3}, "colourspace 3 is not one"),
            ({"domain": {"sun_zenith": [0, 1.6], "turbidity": [2.5, 6.0]}}, "metadata domain"),
            ({"basis": "monomials"}, "metadata basis"),
            ({"degrees": [[1, 1]]}, "metadata degrees"),
            ({"bands": 2}, "metadata bands"),
            ({"bands": True}, "metadata bands"),
            ({"x": float("nan")}, "metadata must be JSON"),
            ({"x": object()}, "metadata must be JSON"),
            ({"x": "y" * cf.MAX_METADATA_BYTES}, "above MAX_METADATA_BYTES"),
        ],
        ids=["unknown-colourspace", "colourspace-type", "domain", "basis", "degrees", "bands", "bands-bool", "nan",
             "object", "too-large"],
    )
    def test_metadata_refused(self, tmp_path: Path, metadata: dict, match: str) -> None:
        good = _small_table()
        with pytest.raises(cf.CoefficientFileError, match=match):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=good.table, degrees=good.degrees, metadata=metadata))
        assert not (tmp_path / "x.npz").exists()

    def test_argument_types(self, tmp_path: Path) -> None:
        with pytest.raises(cf.CoefficientFileError, match="sky_table must be a skysh.coefficient_file.SkyTable, got dict"):
            cf.write(tmp_path / "x.npz", {"table": 1})  # type: ignore[arg-type]
        with pytest.raises(cf.CoefficientFileError, match="path must be a str or os.PathLike"):
            cf.write(7, _small_table())  # type: ignore[arg-type]
        with pytest.raises(cf.CoefficientFileError, match="table must be a numpy array of floats, got list"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table=[[1.0]], degrees=np.zeros((1, 2), np.int64)))  # type: ignore[arg-type]

    def test_existing_file_replaced_whole(self, tmp_path: Path) -> None:
        path = tmp_path / "t.npz"
        path.write_bytes(b"old" * 100000)
        cf.write(path, _small_table())
        assert cf.read(path).bands == 3 and sorted(p.name for p in tmp_path.iterdir()) == ["t.npz"]

    def test_runtime_constructor_validates(self) -> None:
        bad = _small_table()
        with pytest.raises(cf.CoefficientFileError, match="table must have shape"):
            SkySH(cf.SkyTable(table=bad.table[:, :-1], degrees=bad.degrees, metadata={}))
        with pytest.raises(cf.CoefficientFileError, match="colourspace 'Nope' is not one"):
            SkySH(cf.SkyTable(table=bad.table, degrees=bad.degrees, metadata={"colourspace": "Nope"}))
