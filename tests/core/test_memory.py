"""The one memory guard (camplace.core.memory): the limit, and one wording of a refusal."""

from __future__ import annotations

import pytest

from camplace.core.errors import InputError
from camplace.core.memory import check_grid_memory, check_memory, memory_limit_bytes


def test_memory_limit_from_environment(monkeypatch):
    monkeypatch.setenv("CAMPLACE_MAX_MEMORY_GB", "1.5")
    assert memory_limit_bytes() == int(1.5 * 1024**3)
    monkeypatch.setenv("CAMPLACE_MAX_MEMORY_GB", "-2")
    with pytest.raises(InputError, match="positive"):
        memory_limit_bytes()
    monkeypatch.delenv("CAMPLACE_MAX_MEMORY_GB")
    assert memory_limit_bytes() > 0


def test_memory_check_names_the_numbers():
    with pytest.raises(InputError, match=r"test: a 2000x2000x2000 grid would need 8e\+09 cells of 7 bytes "
                                         r"\(52.2 GiB of memory, limit 4.0 GiB\)") as e:
        check_grid_memory((2000, 2000, 2000), 7, "test", limit=4 * 1024**3)
    assert e.value.option == "max_memory_bytes" and "--" not in str(e.value)
    assert check_grid_memory((10, 10, 10), 7, "test") == 7000


def test_check_memory_wording_without_a_count():
    with pytest.raises(InputError, match=r"^s.yaml: x would need about 3.0 GiB of memory \(limit 2.0 GiB\); "
                                         r"use less, or raise the limit \(max_memory_bytes\) or set CAMPLACE_MAX_MEMORY_GB$"):
        check_memory(3 * 1024**3, "s.yaml: x", "use less", limit=2 * 1024**3)
    assert check_memory(1024, "x", "use less", limit=2048) == 1024
