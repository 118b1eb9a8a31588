"""
Tests of :mod:`skysh.table.coefficient_file`
======================================

The format (version 4) and its writer: round trips (identical arrays, the sky's,
the sun's and the irradiance's, metadata as stored), byte-for-byte determinism,
members read by independent readers (:mod:`zipfile`, :func:`numpy.load`), the
content hash recomputed here from its documented definition with :mod:`hashlib`,
the bounds (a file at every bound is accepted), the colourspace list checked
against colour-science, the ordinary refusals of the reader (versions 1 to 3 by
name) and the writer, and the named-table scheme: a further table added by one
:class:`~skysh.table.coefficient_file.TableSpec`, with no other change.
Hostile and corrupted files are in tests/table/test_corrupt_file.py.

Files that the package's writer refuses to write are made here with
:func:`numpy.savez` (an independent writer). No tolerances: a round trip must
be bit-exact.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import canonical_json

from skysh.domain import SKY, SUN, TERM_ORDER
from skysh.runtime import SkySH
from skysh.table import coefficient_file as cf
from skysh.table import sun_table

ENTRIES: tuple[str, ...] = ("format", "format_version", "table", "degrees", "sun_table", "sun_degrees", "irradiance_table",
                             "irradiance_degrees", "metadata")

SRGB_FROM_XYZ: list[list[float]] = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]
"""An XYZ -> RGB matrix for the synthetic tables (IEC 61966-2-1's rounded sRGB; any 3 x 3 within bounds would do)."""


@pytest.fixture(scope="module")
def shipped_entries() -> dict[str, np.ndarray]:
    """The raw entries of the shipped file (numpy's own reader)."""
    with np.load(cf.default_path(), allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def _sun(seed: int = 1, degrees: tuple[int, int] = (3, 2)) -> cf.NamedTable:
    table = np.random.default_rng(seed).normal(size=((degrees[0] + 1) * (degrees[1] + 1), 1, 3))
    return cf.NamedTable(table=table, degrees=np.array([degrees], dtype=np.int64))


def _irradiance(seed: int = 2, degrees: tuple[int, int] = (4, 2)) -> cf.NamedTable:
    table = np.random.default_rng(seed).normal(size=((degrees[0] + 1) * (degrees[1] + 1), 6, 3))
    return cf.NamedTable(table=table, degrees=np.tile(np.array(degrees, dtype=np.int64), (3, 1)))


RECORDED: dict[str, Any] = {"objective": {"method": "blend"}, "margin": 0.001, "fit_error": {"worst": 0.002},
                            "nonnegativity": {"negative": 0, "points": 12004}}
"""What the irradiance block must record (any JSON values: the format requires the fields, not their figures)."""


def _small_table(bands: int = 3, degrees: tuple[int, int] = (4, 2), seed: int = 0) -> cf.SkyTable:
    rng = np.random.default_rng(seed)
    table = rng.normal(size=((degrees[0] + 1) * (degrees[1] + 1), bands * (bands + 1) // 2, 3))
    metadata = {"colourspace": "sRGB", "errors": {"by_bands": {"1": {"e_mean_worst": 1e-5}}}, "note": "ünïcode ✓",
                "nested": [1, 2.5, None, True], "tables": {"sun": {"rgb_from_xyz": SRGB_FROM_XYZ, "errors": {"worst": 1e-6}},
                                                          "irradiance": RECORDED}}
    return cf.SkyTable(table=table, degrees=np.tile(np.array(degrees, dtype=np.int64), (bands, 1)), metadata=metadata,
                       tables={"sun": _sun(), "irradiance": _irradiance()})


def _irradiance_block(degrees: list[list[int]], colourspace: str = "sRGB") -> dict[str, Any]:
    """The block write() stores for the irradiance: the format's fixed fields, degrees, colourspace, what was recorded."""
    fields = {"basis": cf.IRRADIANCE_BASIS, "domain": cf.DOMAIN, "term_order": TERM_ORDER,
              "units": "cd/m^2 x sr (irradiance; lux for the luminance), linear RGB"}
    return {**fields, "colourspace": colourspace, "degrees": degrees, **RECORDED}


def _sun_block(degrees: list[list[int]], colourspace: str = "sRGB", **extra: Any) -> dict[str, Any]:
    """The block write() stores for the sun: the format's fixed fields (typed from the module), degrees, colourspace."""
    fields = {"air_mass_range": list(SUN.x.fitted), "basis": sun_table.SUN_BASIS, "domain": cf.DOMAIN,
              "term_order": TERM_ORDER, "units": sun_table.SUN_UNITS, "variables": sun_table.SUN_VARIABLES}
    return {**fields, "colourspace": colourspace, "degrees": degrees, **extra}


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
    tables = {name: cf.NamedTable(entries[f"{name}_table"], entries[f"{name}_degrees"]) for name in ("sun", "irradiance")}
    metadata[cf.HASH_KEY] = cf.content_sha256(entries["table"], entries["degrees"], metadata, tables)
    return dict(entries, metadata=np.frombuffer(canonical_json(metadata), dtype=np.uint8))


class TestRoundTrip:
    def test_identical_arrays_and_metadata(self, tmp_path: Path) -> None:
        original = _small_table()
        path = cf.write(tmp_path / "sub" / "table.npz", original)  # creates the folder
        assert path == tmp_path / "sub" / "table.npz" and path.is_file()
        back = cf.read(path)
        np.testing.assert_array_equal(back.table, original.table)
        np.testing.assert_array_equal(back.degrees, original.degrees)
        assert back.table.dtype == np.float64 and back.degrees.dtype == np.int64
        assert list(back.tables) == ["sun", "irradiance"]
        np.testing.assert_array_equal(back.tables["sun"].table, original.tables["sun"].table)
        np.testing.assert_array_equal(back.tables["sun"].degrees, [[3, 2]])
        assert back.tables["sun"].max_degrees == (3, 2)
        np.testing.assert_array_equal(back.tables["irradiance"].table, original.tables["irradiance"].table)
        assert back.tables["irradiance"].degrees.tolist() == [[4, 2]] * 3
        # Stored: the caller's metadata plus the runtime fields, the blocks filled in, and the hash.
        sun = _sun_block([[3, 2]], rgb_from_xyz=SRGB_FROM_XYZ, errors={"worst": 1e-6})
        added = {"domain": cf.DOMAIN, "basis": cf.BASIS, "term_order": TERM_ORDER, "degrees": [[4, 2]] * 3, "bands": 3,
                 "tables": {"sun": sun, "irradiance": _irradiance_block([[4, 2]] * 3)}}
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
        metadata = {"tables": {"sun": {"rgb_from_xyz": SRGB_FROM_XYZ}, "irradiance": RECORDED}}
        tables = {"sun": _sun(), "irradiance": _irradiance()}
        back = cf.read(cf.write(tmp_path / "t.npz", cf.SkyTable(table, degrees, metadata, tables)))
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
            assert data["format_version"].dtype == np.int64 and int(data["format_version"]) == cf.FORMAT_VERSION == 4
            assert data["table"].dtype == np.float64 and data["table"].shape == (15, 6, 3)
            assert data["sun_table"].dtype == np.float64 and data["sun_table"].shape == (12, 1, 3)
            assert data["sun_degrees"].dtype == np.int64 and data["sun_degrees"].tolist() == [[3, 2]]
            assert data["irradiance_table"].dtype == np.float64 and data["irradiance_table"].shape == (15, 6, 3)
            assert data["irradiance_degrees"].dtype == np.int64 and data["irradiance_degrees"].tolist() == [[4, 2]] * 3
            raw = bytes(data["metadata"])
        metadata = json.loads(raw.decode("ascii"))
        assert metadata == cf.read(path).metadata and raw == canonical_json(metadata)  # canonical JSON, as documented

    def test_deterministic_bytes(self, tmp_path: Path) -> None:
        a = cf.write(tmp_path / "a.npz", _small_table()).read_bytes()
        b = cf.write(tmp_path / "b.npz", _small_table()).read_bytes()
        assert a == b
        assert cf.write(tmp_path / "a.npz", cf.read(tmp_path / "a.npz")).read_bytes() == a  # rewrite of a read table

    def test_content_hash_definition(self, tmp_path: Path) -> None:
        back = cf.read(cf.write(tmp_path / "t.npz", _small_table()))
        digest = hashlib.sha256(b"skysh-coefficients\n4\n")
        digest.update(f"table <f8 [15, 6, 3] {15 * 6 * 3 * 8}\n".encode())
        digest.update(back.table.astype("<f8").tobytes())
        digest.update(f"degrees <i8 [3, 2] {3 * 2 * 8}\n".encode())
        digest.update(back.degrees.astype("<i8").tobytes())
        digest.update(f"sun_table <f8 [12, 1, 3] {12 * 3 * 8}\n".encode())
        digest.update(back.tables["sun"].table.astype("<f8").tobytes())
        digest.update(f"sun_degrees <i8 [1, 2] {2 * 8}\n".encode())
        digest.update(back.tables["sun"].degrees.astype("<i8").tobytes())
        digest.update(f"irradiance_table <f8 [15, 6, 3] {15 * 6 * 3 * 8}\n".encode())
        digest.update(back.tables["irradiance"].table.astype("<f8").tobytes())
        digest.update(f"irradiance_degrees <i8 [3, 2] {3 * 2 * 8}\n".encode())
        digest.update(back.tables["irradiance"].degrees.astype("<i8").tobytes())
        text = canonical_json({k: v for k, v in back.metadata.items() if k != cf.HASH_KEY})
        digest.update(f"metadata {len(text)}\n".encode() + text)
        assert back.metadata[cf.HASH_KEY] == digest.hexdigest()
        assert cf.content_sha256(back.table, back.degrees, back.metadata, back.tables) == digest.hexdigest()
        # Negative control: the hash moves with any number and any metadata field.
        changed = back.table.copy()
        changed[0, 0, 0] = np.nextafter(changed[0, 0, 0], np.inf)
        assert cf.content_sha256(changed, back.degrees, back.metadata, back.tables) != digest.hexdigest()
        sun = back.tables["sun"].table.copy()
        sun[-1, 0, 2] = np.nextafter(sun[-1, 0, 2], -np.inf)
        changed_sun = dict(back.tables, sun=cf.NamedTable(sun, back.tables["sun"].degrees))
        assert cf.content_sha256(back.table, back.degrees, back.metadata, changed_sun) != digest.hexdigest()
        irradiance = back.tables["irradiance"].table.copy()
        irradiance[3, 5, 1] = np.nextafter(irradiance[3, 5, 1], np.inf)
        changed_irradiance = dict(back.tables, irradiance=cf.NamedTable(irradiance, back.tables["irradiance"].degrees))
        assert cf.content_sha256(back.table, back.degrees, back.metadata, changed_irradiance) != digest.hexdigest()
        assert cf.content_sha256(back.table, back.degrees, back.metadata) != digest.hexdigest()  # without the tables
        assert cf.content_sha256(back.table, back.degrees, dict(back.metadata, colourspace="ACEScg"),
                                 back.tables) != digest.hexdigest()

    def test_read_arrays_are_read_only(self, tmp_path: Path) -> None:
        back = cf.read(cf.write(tmp_path / "t.npz", _small_table()))
        with pytest.raises(ValueError):
            back.table[0, 0, 0] = 1.0
        with pytest.raises(ValueError):
            back.degrees[0, 0] = 1
        with pytest.raises(ValueError):
            back.tables["sun"].table[0, 0, 0] = 1.0
        with pytest.raises(ValueError):
            back.tables["irradiance"].degrees[0, 0] = 1

    def test_shipped_file(self, tmp_path: Path) -> None:
        sky = cf.read()
        assert sky.bands == 7 and sky.table.shape == (112, 28, 3) and sky.colourspace == "sRGB"
        assert sky.tables["sun"].table.shape == (91, 1, 3) and sky.tables["sun"].degrees.tolist() == [[12, 6]]
        assert sky.tables["irradiance"].table.shape == (112, 6, 3)
        assert sky.tables["irradiance"].degrees.tolist() == [[13, 7]] * 3
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
        assert cf.MAX_MEMBER_BYTES["sun_table.npy"] - 256 == (cf.MAX_FILE_DEGREE + 1) ** 2 * 1 * 3 * 8
        assert cf.MAX_MEMBER_BYTES["sun_degrees.npy"] - 256 == 2 * 8
        assert cf.MAX_MEMBER_BYTES["irradiance_table.npy"] - 256 == (cf.MAX_FILE_DEGREE + 1) ** 2 * 6 * 3 * 8
        assert cf.MAX_MEMBER_BYTES["irradiance_degrees.npy"] - 256 == 3 * 2 * 8
        assert cf.MEMBERS == tuple(f"{e}.npy" for e in ENTRIES) == cf.REQUIRED_MEMBERS
        assert cf.MAX_FILE_BYTES < 1 << 20  # "a hostile file costs a few megabytes"

    def test_largest_file_is_accepted(self, tmp_path: Path) -> None:
        """Every bound at once (bands, degrees, metadata): written, within MAX_FILE_BYTES, read back."""
        bands, top = cf.MAX_FILE_BANDS, cf.MAX_FILE_DEGREE
        table = np.random.default_rng(3).uniform(-cf.MAX_TABLE_MAGNITUDE, cf.MAX_TABLE_MAGNITUDE,
                                                 ((top + 1) ** 2, bands * (bands + 1) // 2, 3))
        # The sun at its bounds too: every channel's |values| summing to SUN_MAX_LN, the matrix at MAX_MATRIX_ENTRY.
        sun = np.full(((top + 1) ** 2, 1, 3), sun_table.SUN_MAX_LN / (top + 1) ** 2)
        sun[::2] *= -1.0
        matrix = [[cf.MAX_MATRIX_ENTRY, -cf.MAX_MATRIX_ENTRY, 0]] * 3
        metadata = {"colourspace": "ACES2065-1", "padding": "x" * (cf.MAX_METADATA_BYTES - 3500),
                    "tables": {"sun": {"rgb_from_xyz": matrix}, "irradiance": RECORDED}}
        irradiance = np.random.default_rng(4).uniform(-cf.MAX_TABLE_MAGNITUDE, cf.MAX_TABLE_MAGNITUDE, ((top + 1) ** 2, 6, 3))
        tables = {"sun": cf.NamedTable(sun, np.array([[top, top]])),
                  "irradiance": cf.NamedTable(irradiance, np.full((3, 2), top, dtype=np.int64))}
        path = cf.write(tmp_path / "big.npz", cf.SkyTable(table, np.full((bands, 2), top, dtype=np.int64), metadata, tables))
        assert cf.MAX_FILE_BYTES - 4096 < path.stat().st_size <= cf.MAX_FILE_BYTES
        back = cf.read(path)
        np.testing.assert_array_equal(back.table, table)
        np.testing.assert_array_equal(back.tables["sun"].table, sun)
        np.testing.assert_array_equal(back.tables["irradiance"].table, irradiance)

    def test_file_colourspaces_exist_in_colour_science(self) -> None:
        import colour

        for name in cf.FILE_COLOURSPACES:
            assert name in colour.RGB_COLOURSPACES, name
            # Its XYZ -> RGB matrix fits the bound of a table block's matrix (a file can record it).
            assert np.abs(np.asarray(colour.RGB_COLOURSPACES[name].matrix_XYZ_to_RGB)).max() <= cf.MAX_MATRIX_ENTRY
        assert "Not A Colourspace" not in colour.RGB_COLOURSPACES  # negative control of the membership test

    def test_shipped_matrix_is_colour_sciences(self) -> None:
        """The recorded XYZ -> RGB matrix is colour-science's for the file's colourspace, exactly (JSON keeps repr)."""
        import colour

        sky = cf.read()
        expected = colour.RGB_COLOURSPACES[sky.colourspace].matrix_XYZ_to_RGB
        assert sky.metadata["tables"]["sun"]["rgb_from_xyz"] == np.asarray(expected, dtype=np.float64).tolist()
        assert sky.metadata["tables"]["sun"]["colourspace"] == sky.colourspace

    def test_domain_is_the_packages(self) -> None:
        assert cf.DOMAIN == {"sun_zenith": [0.0, np.pi / 2], "turbidity": [2.5, 6.0]}
        assert tuple(cf.DOMAIN["sun_zenith"]) == SKY.x.interval


class TestRefusals:
    @staticmethod
    def _v2_entries(shipped_entries: dict) -> dict:
        """The members of a version 2 file (no sun table), its metadata without the sun's block."""
        metadata = json.loads(bytes(shipped_entries["metadata"]).decode("ascii"))
        metadata.pop("tables")
        entries = {k: v for k, v in shipped_entries.items() if not k.startswith(("sun_", "irradiance_"))}
        return dict(entries, metadata=np.frombuffer(canonical_json(metadata), dtype=np.uint8))

    def test_version_1_names_the_versions(self, tmp_path: Path, shipped_entries: dict) -> None:
        # Version 1 as skysh 0.1.0 wrote it: savez_compressed, metadata a '<U' string, no hash.
        entries = self._v2_entries(shipped_entries)
        metadata = json.loads(bytes(entries["metadata"]).decode("ascii"))
        metadata.pop(cf.HASH_KEY)
        entries = dict(entries, format_version=np.array(1, dtype=np.int64), metadata=np.array(json.dumps(metadata)))
        _refused(_write_raw(tmp_path / "v1.npz", entries, compressed=True),
                 r"format version 1 \(skysh 0.1.0: compressed, no content hash\) is no longer read: this skysh \(.*\) "
                 r"reads format version 4 only.*skysh fit --out")

    def test_version_2_names_the_versions(self, tmp_path: Path, shipped_entries: dict) -> None:
        """A version 2 file (five members, hashed, no sun table): refused by its version, not by what it lacks."""
        entries = dict(self._v2_entries(shipped_entries), format_version=np.array(2, dtype=np.int64))
        _refused(_write_raw(tmp_path / "v2.npz", entries),
                 r"format version 2 \(hashed, without the sun's table\) is no longer read: this skysh \(.*\) reads "
                 r"format version 4 only \(hashed, strictly checked, with the sun's and the irradiance tables\); "
                 r"regenerate the file with `skysh fit --out FILE`")

    def test_version_3_names_the_versions(self, tmp_path: Path, shipped_entries: dict) -> None:
        """A version 3 file (the sky's and the sun's tables, no irradiance table): refused by its version, by name."""
        metadata = json.loads(bytes(shipped_entries["metadata"]).decode("ascii"))
        metadata["tables"].pop("irradiance")
        entries = {k: v for k, v in shipped_entries.items() if not k.startswith("irradiance_")}
        entries.update(format_version=np.array(3, dtype=np.int64), metadata=np.frombuffer(canonical_json(metadata), np.uint8))
        _refused(_write_raw(tmp_path / "v3.npz", entries),
                 r"format version 3 \(without the irradiance table\) is no longer read: this skysh \(.*\) reads format "
                 r"version 4 only \(hashed, strictly checked, with the sun's and the irradiance tables\); regenerate the "
                 r"file with `skysh fit --out FILE` \(tools/fit_sky.py\)")

    @pytest.mark.parametrize("version", [0, 5, -1, 100])
    def test_wrong_format_version(self, tmp_path: Path, shipped_entries: dict, version: int) -> None:
        entries = dict(shipped_entries, format_version=np.array(version, dtype=np.int64))
        _refused(_write_raw(tmp_path / "v.npz", entries), rf"has format version {version}; .* reads format version 4 only")

    @pytest.mark.parametrize("version", [np.array("one"), np.array(1.5), np.array(True)], ids=["string", "fraction", "bool"])
    def test_malformed_format_version(self, tmp_path: Path, shipped_entries: dict, version: np.ndarray) -> None:
        _refused(_write_raw(tmp_path / "v.npz", dict(shipped_entries, format_version=version)), "malformed format version")

    @pytest.mark.parametrize("value", ["other", "skysh-coefficients-v2", ""])
    def test_wrong_format_string(self, tmp_path: Path, shipped_entries: dict, value: str) -> None:
        entries = dict(shipped_entries, format=np.array(value))
        _refused(_write_raw(tmp_path / "f.npz", entries), rf"has format '{value}', expected 'skysh-coefficients'")

    def test_compressed_members(self, tmp_path: Path, shipped_entries: dict) -> None:
        _refused(_write_raw(tmp_path / "c.npz", shipped_entries, compressed=True), "compressed; format version 4 stores")

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
        with pytest.raises(cf.CoefficientFileError, match=r"path must be a str or os.PathLike"):
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

    @pytest.mark.parametrize("table", ["sun", "irradiance"])
    def test_without_a_required_table(self, tmp_path: Path, shipped_entries: dict, table: str) -> None:
        entries = {k: v for k, v in shipped_entries.items() if not k.startswith(f"{table}_")}
        _refused(_write_raw(tmp_path / "m.npz", entries), rf"lacks the members \['{table}_table.npy', '{table}_degrees.npy'\]")

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
            (lambda e: {"sun_table": e["sun_table"][:-1]}, r"sun_table must have shape \(91, 1, 3\).*got \(90, 1, 3\)"),
            (lambda e: {"sun_table": e["sun_table"][:, 0]}, r"sun_table must have shape \(91, 1, 3\)"),
            (lambda e: {"sun_table": np.repeat(e["sun_table"], 3, axis=1)}, r"sun_table must have shape \(91, 1, 3\)"),
            (lambda e: {"sun_degrees": np.array([[12, 6], [12, 6]])}, r"sun_degrees must have shape \(groups, 2\) with 1 <= "
             r"groups <= 1"),
            (lambda e: {"sun_degrees": np.array([[12, 5]])}, r"sun_table must have shape \(78, 1, 3\)"),
            (lambda e: {"sun_degrees": np.array([[32, 6]])}, r"sun_degrees must lie in \[0, 31\]"),
            (lambda e: {"irradiance_table": e["irradiance_table"][:, :5]}, r"irradiance_table must have shape \(112, 6, 3\)"),
            (lambda e: {"irradiance_degrees": e["irradiance_degrees"][:2]}, r"irradiance_degrees must have shape \(groups, "
             r"2\) with 3 <= groups <= 3"),
            (lambda e: {"irradiance_degrees": np.full((3, 2), [13, 6])}, r"irradiance_table must have shape \(98, 6, 3\)"),
        ],
        ids=["terms", "rows", "channels", "ndim", "bands-vs-rows", "degree-columns", "degrees-1d", "no-bands",
             "too-many-bands", "negative-degree", "degree-too-high", "sun-terms", "sun-2d", "sun-rows", "sun-groups",
             "sun-degrees-vs-terms", "sun-degree-too-high", "irradiance-rows", "irradiance-groups",
             "irradiance-degrees-vs-terms"],
    )
    def test_inconsistent_shapes(self, tmp_path: Path, shipped_entries: dict, change, match: str) -> None:
        _refused(_write_raw(tmp_path / "s.npz", dict(shipped_entries, **change(shipped_entries))), match)

    @pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
    @pytest.mark.parametrize("entry", ["table", "sun_table", "irradiance_table"])
    def test_non_finite_table(self, tmp_path: Path, shipped_entries: dict, value: float, entry: str) -> None:
        table = shipped_entries[entry].copy()
        table[5, 0, 1] = value
        _refused(_write_raw(tmp_path / "n.npz", dict(shipped_entries, **{entry: table})), f"{entry} holds NaN or inf")

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
            cf.write(tmp_path / "x.npz", cf.SkyTable(good.table, good.degrees, {**good.metadata, **metadata}, good.tables))
        assert not (tmp_path / "x.npz").exists()

    @pytest.mark.parametrize(
        "block, match",
        [
            ({}, r"metadata tables\['sun'\] lacks the fields \['rgb_from_xyz'\]"),
            ({"rgb_from_xyz": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]}, "rgb_from_xyz must be a 3 x 3 list of numbers within"),
            ({"rgb_from_xyz": [[16.5, 0, 0], [0, 1, 0], [0, 0, 1]]}, r"within \+-16"),
            ({"rgb_from_xyz": [[True, 0, 0], [0, 1, 0], [0, 0, 1]]}, "rgb_from_xyz must be"),
            ({"rgb_from_xyz": [["1", 0, 0], [0, 1, 0], [0, 0, 1]]}, "rgb_from_xyz must be"),
            ({"rgb_from_xyz": "identity"}, "rgb_from_xyz must be"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "units": "lux"}, r"tables\['sun'\] units 'lux' differs"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "air_mass_range": [1.0, 36.5]}, "air_mass_range .* differs"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "variables": {"x": "theta"}}, "variables .* differs"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "basis": cf.BASIS}, r"tables\['sun'\] basis .* differs"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "colourspace": "ACEScg"}, "colourspace 'ACEScg' differs from 'sRGB'"),
            ({"rgb_from_xyz": SRGB_FROM_XYZ, "degrees": [[4, 2]]}, r"degrees \[\[4, 2\]\] differs from \[\[3, 2\]\]"),
            ("a block", r"tables\['sun'\] must be a JSON object"),
        ],
        ids=["no-matrix", "matrix-shape", "matrix-entry", "matrix-bool", "matrix-text", "matrix-str", "units",
             "air-mass", "variables", "basis", "colourspace", "degrees", "not-object"],
    )
    def test_sun_block_refused(self, tmp_path: Path, block: Any, match: str) -> None:
        good = _small_table()
        with pytest.raises(cf.CoefficientFileError, match=match):
            metadata = {"tables": {"sun": block, "irradiance": RECORDED}}
            cf.write(tmp_path / "x.npz", cf.SkyTable(good.table, good.degrees, metadata, good.tables))
        assert not (tmp_path / "x.npz").exists()

    def test_sun_table_refused(self, tmp_path: Path) -> None:
        good = _small_table()

        def write(tables: Any, metadata: dict | None = None) -> None:
            meta = good.metadata if metadata is None else metadata
            cf.write(tmp_path / "x.npz", cf.SkyTable(good.table, good.degrees, meta, tables))

        with pytest.raises(cf.CoefficientFileError, match=r"holds the tables \['sun', 'irradiance'\]; this SkyTable has none"):
            write({}, {})
        with pytest.raises(cf.CoefficientFileError, match=r"holds the tables \['irradiance'\]; this SkyTable has none"):
            write({"sun": _sun()}, {"tables": {"sun": {"rgb_from_xyz": SRGB_FROM_XYZ}}})
        with pytest.raises(cf.CoefficientFileError, match=r"tables\['irradiance'\] lacks the fields \['objective', 'margin', "
                           r"'fit_error', 'nonnegativity'\] the format requires"):
            write(good.tables, {"tables": {"sun": {"rgb_from_xyz": SRGB_FROM_XYZ}}})
        with pytest.raises(cf.CoefficientFileError, match=r"irradiance_table holds \|value\| 2e\+04, above 10000"):
            write({"sun": _sun(), "irradiance": cf.NamedTable(np.full((15, 6, 3), 2e4), np.full((3, 2), [4, 2]))})
        with pytest.raises(cf.CoefficientFileError, match=r"sun_table holds \|value\| 101, above 100 \(SUN_MAX_LN\)"):
            write({"sun": cf.NamedTable(np.full((12, 1, 3), 101.0) * (np.arange(12) == 0)[:, None, None], np.array([[3, 2]]))})
        with pytest.raises(cf.CoefficientFileError, match=r"sun_table sums \|values\| to 108 in a channel, above 100"):
            write({"sun": cf.NamedTable(np.full((12, 1, 3), 9.0), np.array([[3, 2]]))})
        with pytest.raises(cf.CoefficientFileError, match="unknown table 'moon'"):
            write({"sun": _sun(), "moon": _sun()})
        with pytest.raises(cf.CoefficientFileError, match=r"tables\['sun'\] .*NamedTable.*tuple"):
            write({"sun": (_sun().table, _sun().degrees)})
        with pytest.raises(cf.CoefficientFileError, match=r"^tables .*list"):
            write([_sun()])
        with pytest.raises(cf.CoefficientFileError, match=r"metadata tables describes \['moon', 'sun'\]; the tables held are "
                           r"\['irradiance', 'sun'\]"):
            write(good.tables, {"tables": {"sun": {"rgb_from_xyz": SRGB_FROM_XYZ}, "moon": {}}})
        with pytest.raises(cf.CoefficientFileError, match=r"metadata tables .*list"):
            write(good.tables, {"tables": []})
        assert not (tmp_path / "x.npz").exists()

    def test_argument_types(self, tmp_path: Path) -> None:
        with pytest.raises(cf.CoefficientFileError, match=r"^sky_table .*SkyTable.*dict"):
            cf.write(tmp_path / "x.npz", {"table": 1})  # type: ignore[arg-type]
        with pytest.raises(cf.CoefficientFileError, match=r"path must be a str or os.PathLike"):
            cf.write(7, _small_table())  # type: ignore[arg-type]
        with pytest.raises(cf.CoefficientFileError, match=r"^table .*list"):
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
        # In memory the sun's table is optional: a sky alone still serves the sky.
        assert SkySH(cf.SkyTable(bad.table, bad.degrees, {})).coefficients(0.5, 3.0).shape == (9, 3)


# --------------------------------------------------------------------------- #
# The named-table scheme: a further table is one TableSpec
# --------------------------------------------------------------------------- #
EXTRA = cf.TableSpec(
    name="extra", required=False, groups=(2, 2),
    fields={"basis": cf.BASIS, "domain": cf.DOMAIN, "term_order": TERM_ORDER, "units": "test: radiance"},
    max_magnitude=cf.MAX_TABLE_MAGNITUDE,
)
"""A further table (2 bands of the sky's form), optional, as a test declares it."""


@pytest.fixture()
def with_extra(monkeypatch: pytest.MonkeyPatch) -> pytest.MonkeyPatch:
    """The format with EXTRA added to TABLES and nothing else changed by hand (the layout derived by _layout)."""
    tables = cf.TABLES + (EXTRA,)
    layout = cf._layout(tables)
    for name, value in zip(("TABLES", "MEMBERS", "REQUIRED_MEMBERS", "MAX_MEMBER_BYTES", "MAX_FILE_BYTES"), (tables, *layout)):
        monkeypatch.setattr(cf, name, value)
    return monkeypatch


def _with_extra_table(seed: int = 7) -> cf.SkyTable:
    base = _small_table()
    extra = cf.NamedTable(np.random.default_rng(seed).normal(size=(15, 3, 3)), np.full((2, 2), [4, 2]))
    return cf.SkyTable(base.table, base.degrees, base.metadata, {**base.tables, "extra": extra})


class TestNamedTableScheme:
    def test_layout(self, with_extra: pytest.MonkeyPatch) -> None:
        assert cf.MEMBERS[-3:] == ("extra_table.npy", "extra_degrees.npy", "metadata.npy")
        assert "extra_table.npy" not in cf.REQUIRED_MEMBERS and cf.MAX_FILE_BYTES < 1 << 20
        assert {"irradiance_table.npy", "sun_table.npy"} <= set(cf.REQUIRED_MEMBERS)

    def test_round_trip_and_hash(self, tmp_path: Path, with_extra: pytest.MonkeyPatch) -> None:
        path = cf.write(tmp_path / "i.npz", _with_extra_table())
        back = cf.read(path)
        np.testing.assert_array_equal(back.tables["extra"].table, _with_extra_table().tables["extra"].table)
        assert back.metadata["tables"]["extra"]["units"] == "test: radiance"
        assert cf.write(tmp_path / "again.npz", back).read_bytes() == path.read_bytes()
        with zipfile.ZipFile(path) as archive:
            assert [i.filename for i in archive.infolist()] == list(cf.MEMBERS)
        extra = back.tables["extra"]
        changed = dict(back.tables, extra=cf.NamedTable(extra.table * 1.0001, extra.degrees))
        assert cf.content_sha256(back.table, back.degrees, back.metadata, changed) != back.metadata[cf.HASH_KEY]

    def test_optional(self, tmp_path: Path, with_extra: pytest.MonkeyPatch) -> None:
        """Files without the optional table (written before it existed) still read."""
        assert cf.read(cf.default_path()).tables.keys() == {"sun", "irradiance"}
        with np.load(cf.write(tmp_path / "i.npz", _with_extra_table()), allow_pickle=False) as data:
            entries = {key: data[key] for key in data.files}
        half = {k: v for k, v in entries.items() if k != "extra_degrees"}
        _refused(_write_raw(tmp_path / "h.npz", half), r"lacks the members \['extra_degrees.npy'\]")

    def test_block_checked(self, tmp_path: Path, with_extra: pytest.MonkeyPatch) -> None:
        table = _with_extra_table()
        metadata = {**table.metadata, "tables": {**table.metadata["tables"], "extra": {"basis": "monomials"}}}
        with pytest.raises(cf.CoefficientFileError, match=r"tables\['extra'\] basis 'monomials' differs"):
            cf.write(tmp_path / "x.npz", cf.SkyTable(table.table, table.degrees, metadata, table.tables))

    def test_unknown_without_the_spec(self, tmp_path: Path, with_extra: pytest.MonkeyPatch) -> None:
        path = cf.write(tmp_path / "i.npz", _with_extra_table())
        with_extra.undo()  # this skysh's format: no such table
        _refused(path, r"holds 11 members including unexpected ones \['extra_degrees.npy', 'extra_table.npy'\]")

    def test_in_memory_block_of_a_known_table_not_held(self) -> None:
        """A SkyTable in memory may describe a known table it does not hold (it serves without it); not an unknown one."""
        good = _small_table()
        cf.SkyTable(good.table, good.degrees, good.metadata, {"sun": good.tables["sun"]}).validate()
        with pytest.raises(cf.CoefficientFileError, match=r"metadata tables describes \['irradiance', 'moon', 'sun'\]"):
            cf.SkyTable(good.table, good.degrees, {"tables": {**good.metadata["tables"], "moon": {}}}, good.tables).validate()
