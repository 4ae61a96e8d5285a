"""camplace.outputs.plan_dxf.cells_outline: the outline of a region's target cells."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given, settings, strategies as st

from camplace.outputs.plan_dxf import cells_outline


def _union(xy, cell):
    h = cell / 2
    return shapely.union_all(shapely.box(xy[:, 0] - h, xy[:, 1] - h, xy[:, 0] + h, xy[:, 1] + h))


def test_l_shape_and_a_ring_with_its_hole_by_hand():
    ell = np.array([[0.25, 0.25], [0.75, 0.25], [0.25, 0.75]])  # three 0.5 m cells
    g = cells_outline(ell, 0.5).simplify(1e-6)
    assert g.geom_type == "Polygon" and abs(g.area - 0.75) < 1e-12
    assert len(g.exterior.coords) == 7  # 6 corners, closed
    ring = np.array([[x, y] for x in range(3) for y in range(3) if (x, y) != (1, 1)], float) * 0.1 + 3.05
    g = cells_outline(ring, 0.1)
    assert len(g.interiors) == 1 and abs(g.area - 0.08) < 1e-12 and abs(shapely.Polygon(g.interiors[0]).area - 0.01) < 1e-12


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 12), st.integers(0, 12)), min_size=1, max_size=80, unique=True),
       st.sampled_from([0.1, 0.2, 0.25, 0.3]), st.floats(-50, 50))
def test_same_region_as_the_union_of_the_squares(cells, cell, offset):
    xy = offset + (np.array(cells, float) + 0.5) * cell
    g, ref = cells_outline(xy, cell), _union(xy, cell)
    assert abs(g.area - len(cells) * cell * cell) < 1e-6 * max(1.0, abs(offset))
    assert g.symmetric_difference(ref).area < 1e-9 * max(1.0, abs(offset))


def test_off_grid_centres_take_the_plain_union():
    xy = np.array([[0.0, 0.0], [0.37, 0.11], [2.0, 2.0]])  # overlapping squares, not on one grid
    g = cells_outline(xy, 0.5)
    assert g.equals(_union(xy, 0.5)) and g.area < 3 * 0.25
