"""The loop products of ffrf/numerics/small_linalg.py against numpy, on the layouts the kernels pass
(contiguous, transposed, strided columns), real and complex, including empty dimensions."""

import numpy as np
import pytest

from ffrf.numerics.small_linalg import cross3, dot, mat_mat, mat_vec, skew, vec_mat


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
def test_products_equal_numpy(rng, dtype):
    def sample(*shape):
        x = rng.standard_normal(shape)
        return (x + 1j * rng.standard_normal(shape)).astype(dtype) if dtype is np.complex128 else x

    a, b, v = sample(4, 3), sample(3, 5), sample(3)
    big = sample(5, 4)
    column = big[:, 1]  # strided
    for left, right in ((a, b), (b.T, a.T), (a.T, big.T)):
        np.testing.assert_allclose(mat_mat(left, right), left @ right, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(mat_vec(a, v), a @ v, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(mat_vec(big.T, column), big.T @ column, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(vec_mat(column, big), column @ big, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(dot(column, big[:, 2]), column @ big[:, 2], rtol=1e-14)
    empty = np.zeros((3, 0), dtype=dtype)
    assert mat_mat(a, empty).shape == (4, 0) and mat_vec(empty, np.zeros(0, dtype=dtype)).tolist() == [0, 0, 0]
    assert dot(np.zeros(0, dtype=dtype), np.zeros(0, dtype=dtype)) == 0
    assert mat_vec(a, v).dtype == dtype and vec_mat(v, b).dtype == dtype


def test_cross3_is_the_cross_product():
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(cross3(a, b), np.cross(a, b), rtol=0, atol=1e-15)


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
def test_skew_matrix_applies_the_cross_product(rng, dtype):
    """skew(a) @ b = a x b (numpy's cross), skew(a) = -skew(a)^T, skew(a) @ a = 0; in a's dtype."""
    a, b = rng.standard_normal(3).astype(dtype), rng.standard_normal(3).astype(dtype)
    if dtype is np.complex128:
        a, b = a + 1j * rng.standard_normal(3), b - 1j * rng.standard_normal(3)
    s = skew(a)
    assert s.dtype == dtype
    np.testing.assert_allclose(s @ b, np.cross(a, b), rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(s, -s.T)
    np.testing.assert_allclose(s @ a, np.zeros(3), atol=1e-14)
    np.testing.assert_array_equal(skew(np.stack([a, b], axis=1)[:, 0]), s)  # a strided column
