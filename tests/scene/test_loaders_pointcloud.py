"""Point-cloud readers/writers: round trips per format, LZF, real PCD, clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.loaders.lzf import lzf_compress_literal, lzf_decompress
from camplace.scene.loaders.pointcloud import (load_point_cloud, voxel_downsample, write_las, write_pcd, write_ply,
                                         write_point_cloud, write_xyz)

SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"


@pytest.fixture(scope="module")
def pts():
    rng = np.random.default_rng(1)
    return rng.uniform([-2, -1, 0], [3, 4, 2.5], size=(500, 3))


@pytest.mark.parametrize("name,tol", [("a.ply", 1e-6), ("a.pcd", 1e-6), ("a.xyz", 1e-5), ("a.csv", 1e-5),
                                      ("a.las", 1e-3), ("a.laz", 1e-3)])
def test_round_trip_each_format(tmp_path, pts, name, tol):
    vps = np.array([[0.5, 1.0, 1.6], [2.0, 2.0, 1.2]])
    write_point_cloud(tmp_path / name, pts, vps)
    pc = load_point_cloud(tmp_path / name)
    assert pc.points.shape == pts.shape
    assert np.allclose(pc.points, pts, atol=tol * 1.01 + 1e-6 * np.abs(pts).max())
    if name.endswith((".ply", ".pcd")):  # scanner viewpoints travel in the header
        assert np.allclose(pc.viewpoints, vps, atol=1e-5)


@pytest.mark.parametrize("data", ["ascii", "binary", "binary_compressed"])
def test_pcd_data_kinds(tmp_path, pts, data):
    write_pcd(tmp_path / "p.pcd", pts, data, viewpoints=[[1.0, 2.0, 3.0]])
    pc = load_point_cloud(tmp_path / "p.pcd")
    assert np.allclose(pc.points, pts, atol=1e-5)
    assert pc.info["pcd_data"] == data
    assert np.allclose(pc.viewpoints, [[1.0, 2.0, 3.0]])


def test_ply_ascii_and_nan_points_dropped(tmp_path, pts):
    bad = pts.copy()
    bad[3] = np.nan
    write_ply(tmp_path / "p.ply", bad, binary=False)
    pc = load_point_cloud(tmp_path / "p.ply")
    assert len(pc) == len(pts) - 1
    assert pc.info["non_finite_dropped"] == 1
    assert pc.info["ply_format"] == "ascii"


def test_text_with_header_and_extra_columns(tmp_path):
    (tmp_path / "p.csv").write_text("x,y,z,intensity\n1,2,3,9\n4,5,6,9\n")
    (tmp_path / "p.txt").write_text("# comment\n1 2 3 0.5 7\n4 5 6 0.5 7\n")
    for f in ("p.csv", "p.txt"):
        assert np.allclose(load_point_cloud(tmp_path / f).points, [[1, 2, 3], [4, 5, 6]])


def test_downsample_while_reading(tmp_path):
    p = np.repeat(np.array([[0.01, 0.01, 0.01], [0.51, 0.01, 0.01]]), 50, axis=0)
    write_ply(tmp_path / "d.ply", p)
    pc = load_point_cloud(tmp_path / "d.ply", downsample=0.1)
    assert len(pc) == 2


def test_voxel_downsample_centroid():
    p = np.array([[0.0, 0.0, 0.0], [0.2, 0.2, 0.2], [1.5, 1.5, 1.5]])
    out = voxel_downsample(p, 1.0)
    assert sorted(map(tuple, np.round(out, 6))) == [(0.1, 0.1, 0.1), (1.5, 1.5, 1.5)]


def test_lzf_literals_and_back_references():
    data = bytes(range(200)) * 3
    assert lzf_decompress(lzf_compress_literal(data), len(data)) == data
    # literal "ab", then a back reference of length 3 at distance 2 -> "ababa"
    stream = bytes([1, ord("a"), ord("b"), 0x20, 1])
    assert lzf_decompress(stream, 5) == b"ababa"
    # length 7 + extra byte: 7 + 2 + 2 = 11 bytes copied from distance 1
    assert lzf_decompress(bytes([0, ord("z"), 0xE0, 2, 0]), 12) == b"z" * 12
    with pytest.raises(ValueError):
        lzf_decompress(bytes([0x20, 5]), 4)  # reference before the start
    with pytest.raises(ValueError):
        lzf_decompress(bytes([5, 1, 2]), 6)  # literal run past the end


@pytest.mark.skipif(not (SHARED / "room_scan1.pcd").is_file(), reason="../shared/data/room_scan1.pcd not present")
def test_real_pcd_binary_compressed():
    pc = load_point_cloud(SHARED / "room_scan1.pcd")
    assert len(pc) == 112_586
    assert pc.info["pcd_data"] == "binary_compressed"
    assert np.allclose(pc.viewpoints, [[0, 0, 0]])
    q1, q99 = np.percentile(pc.points, [1, 99], axis=0)
    assert np.allclose(q1, [-2.63, -3.71, -1.31], atol=0.01)
    assert np.allclose(q99, [7.43, 3.20, 1.70], atol=0.01)


def _one_line(err: InputError) -> str:
    msg = str(err)
    assert "\n" not in msg
    return msg


@pytest.mark.parametrize("name,content,expect", [
    ("e.ply", b"", "empty"),
    ("e.pcd", b"", "empty"),
    ("g.ply", b"ply\nformat nonsense 1.0\nend_header\n", "PLY"),
    ("t.pcd", b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 10\nHEIGHT 1\nPOINTS 10\n"
              b"DATA binary\n\x00\x00\x00\x00", "truncated"),
    ("z.pcd", b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nPOINTS 0\n"
              b"DATA ascii\n", "no points"),
    ("c.pcd", b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
              b"DATA binary_compressed\n\x05\x00\x00\x00\x18\x00\x00\x00\xff\xff\xff\xff\xff", "LZF"),
    ("n.csv", b"a,b,c\nfoo,bar,baz\n", "3 numbers"),
    ("g.las", b"not a las file at all" * 20, "LAS"),
    ("x.e57", b"whatever", "unknown point cloud format"),
])
def test_corrupt_or_empty_files_give_one_line(tmp_path, name, content, expect):
    (tmp_path / name).write_bytes(content)
    with pytest.raises(InputError) as e:
        load_point_cloud(tmp_path / name)
    msg = _one_line(e.value)
    assert expect in msg and name in msg


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_point_cloud(tmp_path / "nope.ply")


def test_writers_reject_unknown_suffix(tmp_path, pts):
    with pytest.raises(InputError):
        write_point_cloud(tmp_path / "a.e57", pts)
    write_xyz(tmp_path / "a.xyz", pts)
    write_las(tmp_path / "b.las", pts)
    assert (tmp_path / "a.xyz").stat().st_size > 0 and (tmp_path / "b.las").stat().st_size > 0


from hypothesis import given, settings, strategies as st  # noqa: E402


@settings(max_examples=50, deadline=None)
@given(st.binary(min_size=0, max_size=300))
def test_lzf_literal_stream_round_trip(data):
    assert lzf_decompress(lzf_compress_literal(data), len(data)) == data


@pytest.mark.parametrize("head, why", [
    (b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n", "no DATA line"),  # header cut short
    (b"# .PCD v0.7\n" + b"".join(b"K%d 1\n" % k for k in range(70)), "not a PCD file"),  # never reaches DATA
])
def test_pcd_header_without_data_line(tmp_path, head, why):
    f = tmp_path / "bad.pcd"
    f.write_bytes(head)
    with pytest.raises(InputError, match=why):
        load_point_cloud(f)


def test_pcd_header_viewpoint_comments_and_data_offset(tmp_path):
    """The header reader keeps camplace's viewpoint comments and stops right after DATA."""
    from camplace.scene.loaders.pointcloud import _pcd_header

    raw = b"# .PCD v0.7\n# viewpoint 1 2 3\n\nFIELDS x y z\nDATA ascii\n0 0 0\n"
    head, pos = _pcd_header(tmp_path / "x.pcd", raw)
    assert head["_VIEWPOINTS"] == [["1", "2", "3"]] and head["FIELDS"] == ["x", "y", "z"]
    assert raw[pos:] == b"0 0 0\n"
