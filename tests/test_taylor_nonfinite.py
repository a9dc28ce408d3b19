"""Joint values that are not finite are refused by every checked evaluation path."""

import warnings

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError, TaylorRadiusWarning
from pinflex.parametric import expand

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def two_link():
    """Benchmark A's planar two-link arm."""
    return FlexibleModel(TWO_LINK, planar=True)


@pytest.mark.parametrize("case", ["two joints", "one joint", "with design"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_joint_values_are_refused(two_link, case, bad):
    """The fast paths (two-joint grid, monomial rows) and the general path refuse them."""
    if case == "two joints":
        tm = expand(two_link, Q0, order=4, modes=(1, 2), design=[])
        Q, kw = np.tile(Q0, (7, 1)) + 0.01, {}
    elif case == "one joint":
        tm = expand(two_link, Q0, order=4, modes=(1,), joints=["q2"], design=[])
        Q, kw = np.tile(Q0, (7, 1)), {}
        Q[:, 1] += 0.01
    else:
        tm = expand(two_link, Q0, order=3, modes=(1,))
        Q, kw = np.tile(Q0, (7, 1)) + 0.01, {"Y": two_link.y0}
    good = tm.evaluate(Q, **kw)
    assert np.all(np.isfinite(good))
    Q = Q.copy()
    Q[4, -1] = bad
    for strict in (False, True):
        with warnings.catch_warnings():
            # no radius warning instead of the error (an infinite offset may make NumPy's
            # arithmetic warn on the way: the fast paths do not pay for an errstate)
            warnings.simplefilter("error", TaylorRadiusWarning)
            warnings.simplefilter("ignore", RuntimeWarning)
            with pytest.raises(ConfigurationError, match="sample 4 are not finite"):
                tm.evaluate(Q, strict=strict, **kw)
    with pytest.raises(ConfigurationError, match="not finite"):
        tm.check_radius(tm.offsets(Q, **kw))
    # with every check off nothing is judged, as documented: the sample's value is not finite
    with np.errstate(all="ignore"):
        off = tm.evaluate(Q, warn=False, **kw)
    assert not np.all(np.isfinite(off[4]))
    np.testing.assert_allclose(np.delete(off, 4, axis=0), np.delete(good, 4, axis=0), rtol=1e-14)
