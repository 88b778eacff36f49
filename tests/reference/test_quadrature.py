"""
``reference.quadrature.gauss_legendre``: beyond 100 nodes Newton's iteration replaces NumPy's
eigenvalue method; both give the same rule, and the rule integrates polynomials exactly.
"""

import math

import numpy as np
import pytest

from mi_brdfs.reference.quadrature import gauss_legendre


@pytest.mark.parametrize("n", [101, 400])
def test01_newton_nodes_equal_numpys(n):
    """The same nodes to rounding; the same weights to NumPy's own accuracy (its weights from
    the eigenvectors lose digits as n grows: test02 shows Newton's are the more exact)."""
    x, w = gauss_legendre(n)
    x_np, w_np = np.polynomial.legendre.leggauss(n)
    np.testing.assert_allclose(x, x_np, rtol=0, atol=1e-14)
    np.testing.assert_allclose(w, w_np, rtol=1e-9, atol=0)


def test02_exact_for_degree_below_2n():
    """∫₋₁¹ x^(2m) dx = 2/(2m + 1) up to degree 2n − 2 (here 2998 with 1500 nodes), and
    ∫₀^π sin: the smooth integrand converges to rounding."""
    x, w = gauss_legendre(1500)
    for m in (0, 1, 10, 500, 1499):
        assert np.sum(w * x ** (2 * m)) == pytest.approx(2.0 / (2 * m + 1), rel=1e-11)
    assert np.sum(w * np.sin((x + 1) * math.pi / 2)) * math.pi / 2 == pytest.approx(2.0,
                                                                                   rel=1e-13)
