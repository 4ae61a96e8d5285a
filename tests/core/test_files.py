"""Atomic writes: never a half-written output (camplace.core.files)."""

from __future__ import annotations

import gc
import re
from pathlib import Path

import numpy as np
import pytest

from camplace.core.files import AtomicBatch, atomic_savez, atomic_write_bytes, atomic_write_json, atomic_write_text

SRC = Path(__file__).resolve().parents[2] / "src" / "camplace"


def _listing(d: Path) -> set[str]:
    return {p.name for p in d.iterdir()}


def test_atomic_write_replaces_whole_file_and_leaves_no_temporary(tmp_path):
    f = tmp_path / "sub" / "a.json"
    atomic_write_json(f, {"a": 1})
    atomic_write_text(f, "new\n")
    assert f.read_text() == "new\n"
    atomic_savez(tmp_path / "z.npz", x=np.arange(3))
    assert np.load(tmp_path / "z.npz")["x"].tolist() == [0, 1, 2]
    assert _listing(f.parent) == {"a.json"}


def test_failing_write_keeps_the_old_file(tmp_path, monkeypatch):
    f = tmp_path / "a.txt"
    atomic_write_text(f, "old")

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("camplace.core.files.os.replace", broken_replace)
    with pytest.raises(OSError):
        atomic_write_bytes(f, b"new")
    assert f.read_text() == "old"
    assert _listing(tmp_path) == {"a.txt"}


def test_batch_commits_all_or_nothing(tmp_path):
    for name in ("a", "b"):
        (tmp_path / name).write_text("old")
    with pytest.raises(RuntimeError):
        with AtomicBatch() as b:
            b.stage_text(tmp_path / "a", "new")
            b.stage_json(tmp_path / "c", [1])
            raise RuntimeError("the report failed half-way")
    assert (tmp_path / "a").read_text() == "old" and _listing(tmp_path) == {"a", "b"}
    with AtomicBatch() as b:
        b.stage_text(tmp_path / "a", "new")
        b.stage_savez(tmp_path / "c.npz", x=np.ones(2))
        assert (tmp_path / "a").read_text() == "old"  # nothing visible before the commit
    assert (tmp_path / "a").read_text() == "new" and _listing(tmp_path) == {"a", "b", "c.npz"}


def test_uncommitted_batch_cleans_up_when_collected(tmp_path):
    b = AtomicBatch()
    b.stage_text(tmp_path / "x", "data")
    assert len(_listing(tmp_path)) == 1 and not (tmp_path / "x").exists()
    del b
    gc.collect()
    assert _listing(tmp_path) == set()


def test_report_failure_keeps_previous_contract_files(tmp_path, demo_run, monkeypatch):
    """write_outputs that fails part-way (here: the report) leaves the old set untouched."""
    from camplace.outputs.write import write_outputs

    r = demo_run
    out = tmp_path / "out"
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  report=False)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("camplace.outputs.report_html.write_report", broken)
    monkeypatch.setattr("camplace.core.files.np.savez_compressed", broken)
    with pytest.raises(OSError):
        write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s)
    gc.collect()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


# a raw write anywhere in the library bypasses the atomic writers; writes into an in-memory
# buffer (buf) or to os.devnull are fine
RAW_WRITE = re.compile(
    r"open\([^)]*['\"][wax]b?\+?['\"]|\.write_text\(|\.write_bytes\(|np\.save(z|z_compressed)?\((?!buf)|"
    r"savefig\((?!buf)|\.to_csv\(|json\.dump\(|write_html\(|shutil\.(copy|move)|tofile\(|\.write\((?!buf)")


def test_library_writes_files_only_through_camplace_files():
    offenders = []
    for f in sorted(SRC.rglob("*.py")):
        if f.name == "files.py":
            continue
        for n, line in enumerate(f.read_text().splitlines(), 1):
            if RAW_WRITE.search(line) and "os.devnull" not in line and not line.lstrip().startswith("#"):
                offenders.append(f"{f.relative_to(SRC)}:{n}: {line.strip()}")
    assert not offenders, "write through camplace.core.files (atomic):\n" + "\n".join(offenders)


def test_written_files_get_the_mode_of_an_ordinary_write(tmp_path):
    """Outputs are readable as any file the user writes: 0666 less the umask (not the
    0600 of a private temporary file); a file that exists keeps its mode."""
    import os
    import stat

    old = os.umask(0o027)
    try:
        plain = tmp_path / "plain.txt"
        plain.write_text("x")
        atomic_write_text(tmp_path / "a.txt", "x")
        atomic_savez(tmp_path / "z.npz", x=np.arange(3))
        with AtomicBatch() as b:
            b.stage_json(tmp_path / "b.json", [1])
        from camplace.core.files import atomic_npy_memmap

        with atomic_npy_memmap(tmp_path / "m.npy", np.uint8, (4,)) as arr:
            arr[:] = 1
        want = stat.S_IMODE(plain.stat().st_mode)
        assert want == 0o640
        for name in ("a.txt", "z.npz", "b.json", "m.npy"):
            assert stat.S_IMODE((tmp_path / name).stat().st_mode) == want, name
        os.chmod(tmp_path / "a.txt", 0o604)
        atomic_write_text(tmp_path / "a.txt", "y")  # rewriting keeps the file's own mode
        assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o604
    finally:
        os.umask(old)


def test_savez_at_a_zlib_level_reads_back_the_same_arrays(tmp_path):
    """Issue 37: visibility.npz at site scale is written at zlib level 1; np.load reads the
    same arrays, the compressed members are smaller than stored, level 9 no larger than 1."""
    rng = np.random.default_rng(0)
    arrays = {"indices": np.sort(rng.integers(0, 5000, 200_000)).astype(np.int32), "data": np.ones(200_000, np.uint8),
              "names": np.array(["a", "bc"])}
    sizes = {}
    for level in (1, 9):
        p = atomic_savez(tmp_path / f"v{level}.npz", level=level, **arrays)
        with np.load(p) as z:
            assert sorted(z.files) == sorted(arrays) and all(np.array_equal(z[k], v) for k, v in arrays.items())
        sizes[level] = p.stat().st_size
    plain = atomic_savez(tmp_path / "plain.npz", compressed=False, **arrays).stat().st_size
    assert sizes[9] <= sizes[1] < plain / 3


def test_atomic_write_texts_writes_every_file_in_order(tmp_path):
    """Issue 37: many small files at once on threads; each whole, none left temporary, the
    paths in the given order, an error raised (the others still written whole or not at all)."""
    from camplace.core.files import atomic_write_texts

    texts = {tmp_path / f"f{k:03d}.txt": f"camera {k}\n" * (k + 1) for k in range(40)}
    assert atomic_write_texts(texts) == list(texts)
    assert all(p.read_text() == t for p, t in texts.items())
    assert sorted(q.name for q in tmp_path.iterdir()) == sorted(p.name for p in texts)  # no temporaries
    assert atomic_write_texts({tmp_path / "one.txt": "x"}) == [tmp_path / "one.txt"]
    with pytest.raises(OSError):
        atomic_write_texts({tmp_path / "a.txt": "a", tmp_path / "f000.txt" / "b": "b"})  # under a file
    assert (tmp_path / "a.txt").read_text() == "a"
