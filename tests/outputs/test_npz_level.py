"""visibility.npz's zlib level (issue 37): level 1 from SITE_NPZ_PAIRS visible pairs on,
numpy's own below (small runs' files unchanged)."""

from __future__ import annotations

from camplace.outputs.write import SITE_NPZ_LEVEL, SITE_NPZ_PAIRS, npz_level


def test_site_scale_level_by_hand():
    assert SITE_NPZ_LEVEL == 1 and SITE_NPZ_PAIRS == 20_000_000
    assert npz_level(0) is None and npz_level(1_670_000) is None  # standard-store: numpy's level
    assert npz_level(SITE_NPZ_PAIRS - 1) is None
    assert npz_level(SITE_NPZ_PAIRS) == 1 and npz_level(922_827_331) == 1  # warehouse:100000
