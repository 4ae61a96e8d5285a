"""Bad space files: every loader either returns a valid cloud / mesh / OctoMap or raises
InputError with one line naming the file; never another exception, never a MemoryError,
never an allocation beyond what the file's size allows (issue 16)."""

from __future__ import annotations

import re
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from camplace.core.errors import InputError
from camplace.scene.loaders.mesh import boxes_to_mesh, load_mesh, write_mesh
from camplace.scene.loaders.octomap import load_octomap, write_octomap
from camplace.scene.loaders.pointcloud import load_point_cloud, write_las, write_pcd, write_ply, write_xyz

from conftest import read_or_one_line

PTS = np.random.default_rng(3).uniform([-1, -1, 0], [2, 1, 1.5], size=(12, 3))
MESH = boxes_to_mesh([(np.zeros(3), np.ones(3)), (np.array([2.0, 0, 0]), np.array([3.0, 1, 0.5]))])
PEAK_BYTES = 64 << 20  # a file of a few KB may not make a loader allocate more than this


def _octomap(path: Path) -> None:
    occ = np.zeros((4, 4, 3), bool)
    occ[1:3, 1:3, 0] = True
    write_octomap(path, occ, ~occ, np.zeros(3), 0.1)


WRITERS = {
    "a.ply": lambda p: write_ply(p, PTS, binary=False),
    "b.ply": lambda p: write_ply(p, PTS, binary=True),
    "a.pcd": lambda p: write_pcd(p, PTS, "ascii"),
    "b.pcd": lambda p: write_pcd(p, PTS, "binary"),
    "c.pcd": lambda p: write_pcd(p, PTS, "binary_compressed"),
    "a.xyz": lambda p: write_xyz(p, PTS),
    "a.csv": lambda p: write_xyz(p, PTS, ","),
    "a.las": lambda p: write_las(p, PTS),
    "a.laz": lambda p: write_las(p, PTS),
    "m.obj": lambda p: write_mesh(p, MESH),
    "m.stl": lambda p: write_mesh(p, MESH),
    "m.glb": lambda p: write_mesh(p, MESH),
    "mesh.ply": lambda p: write_mesh(p, MESH),
    "o.bt": _octomap,
    "o.ot": _octomap,
}


def _load(path: Path):
    """The loader of the file's kind; returns its finite coordinates (K, 3) for checking."""
    if path.suffix in (".bt", ".ot"):
        om = load_octomap(path)
        assert np.all(om.occupied_size > 0) and np.all(om.free_size > 0)
        return np.concatenate([om.occupied_lo, om.free_lo, om.occupied_size[:, None].repeat(3, 1)])
    if path.suffix in (".obj", ".stl", ".glb") or path.name.startswith("mesh"):
        m = load_mesh(path)
        assert len(m.faces) and m.faces.min() >= 0 and m.faces.max() < len(m.vertices)
        return m.vertices
    pc = load_point_cloud(path)
    assert len(pc.points) > 0 and np.all(np.isfinite(pc.viewpoints))
    return pc.points


def _check(path: Path) -> None:
    """The contract: a valid result (finite, non-empty) or one-line InputError naming the file."""
    tracemalloc.start()
    try:
        xyz = read_or_one_line(_load, path)
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < PEAK_BYTES, f"{path.name}: {peak} bytes allocated for a {path.stat().st_size} byte file"
    if xyz is None:
        return
    assert xyz.ndim == 2 and xyz.shape[1] == 3 and len(xyz) > 0 and np.all(np.isfinite(xyz))


@pytest.fixture(scope="module")
def valid(tmp_path_factory) -> dict[str, bytes]:
    d = tmp_path_factory.mktemp("valid")
    out = {}
    for name, write in WRITERS.items():
        write(d / name)
        out[name] = (d / name).read_bytes()
        _load(d / name)  # the unmutated file loads
    return out


def _huge_counts(raw: bytes, name: str, digits: bytes) -> bytes:
    """The first number of the header's count line (or the binary count field) set huge."""
    fields = {".stl": (80, "<u4"), ".las": (107, "<u4"), ".laz": (107, "<u4")}
    suf = Path(name).suffix
    if suf in fields and not name.startswith("mesh"):
        off, dt = fields[suf]
        return raw[:off] + np.array([np.iinfo(dt).max], dt).tobytes() + raw[off + 4:]
    pat = rb"(element vertex |element face |POINTS |WIDTH |size |\"count\":)(\d+)"
    return re.sub(pat, lambda m: m.group(1) + digits, raw, count=1)


def _mutate(raw: bytes, name: str, kind: str, at: float, junk: bytes) -> bytes:
    i = int(at * len(raw))
    if kind == "truncate":
        return raw[:i]
    if kind == "flip":
        i = min(i, len(raw) - 1)
        return raw[:i] + bytes([raw[i] ^ (junk[0] if junk and junk[0] else 0xFF)]) + raw[i + 1:]
    if kind == "insert":
        return raw[:i] + junk + raw[i:]
    return _huge_counts(raw, name, b"1000000000000" if junk[:1] < b"\x80" else b"4294967295")


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(sorted(WRITERS)), kind=st.sampled_from(["truncate", "flip", "insert", "huge"]),
       at=st.floats(0.0, 1.0), junk=st.binary(min_size=1, max_size=24))
def test_mutated_files_load_or_fail_in_one_line(valid, tmp_path_factory, name, kind, at, junk):
    path = tmp_path_factory.mktemp("bad") / name
    path.write_bytes(_mutate(valid[name], name, kind, at, junk))
    _check(path)


# ------------------------------------------------------------------ each defect by hand

PCD_HEAD = (b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
            b"POINTS {n}\nDATA {data}\n")


def _pcd(n: int, data: str, body: bytes) -> bytes:
    return PCD_HEAD.replace(b"{n}", str(n).encode()).replace(b"{data}", data.encode()) + body


def _ply(n: int, fmt: str, body: bytes) -> bytes:
    return (f"ply\nformat {fmt} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
            f"property float z\nend_header\n").encode() + body


F32 = PTS.astype("<f4").tobytes()
HAND = [  # (file name, content, words the message must hold)
    ("trunc.pcd", _pcd(12, "binary", F32[:100]), ["truncated", "promises 12", "only 100 bytes"]),
    ("trunc.ply", _ply(12, "binary_little_endian", F32[:100]), ["promises 12"]),
    ("magic.ply", b"plx\n" + _ply(12, "ascii", b"")[4:], ["not a PLY file"]),
    ("magic.bt", b"# Octomap OcTreX binary file\n", ["not an OctoMap"]),
    ("magic.las", b"LASX" + bytes(400), ["not a LAS/LAZ file"]),
    ("magic.glb", b"glTX" + bytes(40), ["not a GLB file"]),
    ("mismatch.pcd", _pcd(12, "ascii", b"1.000000000 2.000000000 3.000000000\n" * 3), ["3 rows", "header says 12"]),
    ("mismatch.ot", b"# Octomap OcTree file\nid OcTree\nsize 3\nres 0.1\ndata\n" + bytes(5), ["size 3", "holds 1"]),
    ("empty.pcd", _pcd(0, "binary", b""), ["no points"]),
    ("empty.ply", _ply(0, "ascii", b""), ["no finite points"]),
    ("empty.xyz", b"# only a comment\n", ["empty"]),
    ("nan.xyz", b"nan 1 2\ninf 0 0\n1 -inf 3\n", ["no finite points", "3 read"]),
    ("huge.pcd", _pcd(10 ** 12, "binary", F32), ["promises 1,000,000,000,000 points"]),
    ("huge.ply", _ply(10 ** 12, "ascii", b"1 2 3\n"), ["promises 1,000,000,000,000"]),
    ("huge-c.pcd", _pcd(10 ** 12, "binary_compressed", np.array([40, 4000], "<u4").tobytes() + bytes(40)),
     ["promises 1,000,000,000,000"]),
    ("utf.xyz", "1 2 3\n4 5 6 \u00e9\n".encode("latin-1"), ["not UTF-8 text", "0xe9"]),
    ("utf.ply", _ply(1, "ascii", b"1 2 3\n").replace(b"float x", b"float \xe9"), ["not ASCII text"]),
    ("utf.pcd", _pcd(1, "ascii", b"1 2 3\n").replace(b"FIELDS x", b"FIELDS \xff x"), ["not UTF-8"]),
]


@pytest.mark.parametrize("name,content,words", HAND, ids=[h[0] for h in HAND])
def test_each_defect_one_line_naming_the_file(tmp_path, name, content, words):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(InputError) as err:
        _load(path)
    msg = str(err.value)
    assert str(path) in msg and "\n" not in msg
    for w in words:
        assert w in msg, msg
    _check(path)  # and within the memory bound


def test_huge_las_count_refused_before_laspy(tmp_path):
    write_las(tmp_path / "a.las", PTS)
    raw = bytearray((tmp_path / "a.las").read_bytes())
    raw[107:111] = np.array([4_000_000_000], "<u4").tobytes()
    (tmp_path / "a.las").write_bytes(bytes(raw))
    with pytest.raises(InputError, match="promises 4,000,000,000 points"):
        load_point_cloud(tmp_path / "a.las")


def test_huge_laz_chunk_size_refused_before_lazrs(tmp_path):
    # lazrs allocates one chunk of points up front: a flipped chunk size aborted the process
    write_las(tmp_path / "a.laz", PTS)
    raw = bytearray((tmp_path / "a.laz").read_bytes())
    at = raw.index(b"laszip encoded") - 2 + 54 + 12
    raw[at:at + 4] = np.array([4_076_913_488], "<u4").tobytes()
    (tmp_path / "a.laz").write_bytes(bytes(raw))
    with pytest.raises(InputError, match="LAZ chunk size 4,076,913,488"):
        load_point_cloud(tmp_path / "a.laz")


def test_non_finite_points_dropped_and_counted(tmp_path):
    path = tmp_path / "some.xyz"
    path.write_bytes(b"0 0 0\nnan 1 2\n1 1 1\ninf 0 0\n2 2 2\n")
    pc = load_point_cloud(path)
    assert len(pc.points) == 3 and pc.info["non_finite_dropped"] == 2 and pc.info["points_read"] == 5
    from camplace.scene.loaders.obstacles import describe

    line = describe("scan", {"kind": "point_cloud", **pc.info})
    assert "2 non-finite points dropped" in line


# ------------------------------------------------------------------ through the CLI


@pytest.mark.parametrize("name,content,key,words", [
    ("scan.pcd", _pcd(10 ** 12, "binary", F32), "point_cloud", ["promises 1,000,000,000,000 points"]),
    ("map.bt", b"# Octomap OcTree binary file\nid OcTree\nsize 2\nres 0.1\ndata\n\xff", "octomap", ["truncated"]),
])
def test_cli_run_on_a_bad_obstacle_file_exits_2(tmp_path, monkeypatch, capsys, name, content, key, words):
    import yaml
    from conftest import BASE, run_cli

    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    (tmp_path / name).write_bytes(content)
    scene = dict(BASE, obstacles=[{"name": "bad", key: name}])
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene, sort_keys=False))
    out = tmp_path / "out"
    code, text = run_cli(["run", tmp_path / "scene.yaml", "--out", out, "--no-cache"], monkeypatch, capsys)
    assert code == 2, text
    errors = [line for line in text.splitlines() if line.strip()]
    assert "Traceback" not in text and errors[-1].startswith("error:") and len(errors) <= 2, text
    assert name in text and all(w in text for w in words), text
    assert not out.exists()
