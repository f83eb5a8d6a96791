"""The compiled even-odd point-in-polygon test (explorer.kernels.geometry) against matplotlib's
Path.contains_points, an independent implementation, on random simple polygons."""
import numpy as np
from matplotlib.path import Path

from explorer.kernels import geometry


def _star(rng, k):
    """A random simple (star-shaped, non-convex) polygon of k vertices around the origin."""
    th = np.sort(rng.uniform(0, 2 * np.pi, k))
    r = rng.uniform(0.3, 1.0, k)
    return np.c_[r * np.cos(th), r * np.sin(th)]


def test_points_inside_random_star_polygons_agree_with_matplotlib():
    rng = np.random.default_rng(7)
    for k in (5, 17, 400, 3000):
        P = _star(rng, k)
        X = rng.uniform(-1.1, 1.1, (20_000, 2))
        got = geometry.inside(P, X)
        ref = Path(P, closed=False).contains_points(X)
        assert 0.01 < got.mean() < 0.9          # both answers occur
        # a point within round-off of an edge may go either way in the two implementations
        assert np.count_nonzero(got != ref) <= 2, k


def test_nan_points_and_empty_inputs_are_outside():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    assert geometry.inside(square, [[np.nan, 1.0], [1.0, np.nan], [1.0, 1.0]]).tolist() == [False, False, True]
    assert geometry.inside(square, np.empty((0, 2))).shape == (0,)
    assert not geometry.inside(np.empty((0, 2)), [[1.0, 1.0]]).any()
