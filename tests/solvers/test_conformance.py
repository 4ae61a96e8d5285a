"""Every registered solver passes the public conformance suite (camplace.solvers.testing)."""

from __future__ import annotations

from camplace.solvers import SOLVERS
from camplace.solvers.testing import parametrize_with_checks


@parametrize_with_checks(SOLVERS)
def test_solver_conforms(solver, check):
    check(solver)
