"""The public surface of the model: exactly ``erls.model.PUBLIC``; internals are free functions.

As ``pinocchio.Model`` carries data and Pinocchio's algorithms are free functions of
``(model, data, ...)``, ``FlexibleModel`` keeps its data, construction and the documented
queries; what pinflex's layers run on a model (input checks, kinematics terms, assembly)
lives in the modules that own it and takes the model as first argument.
"""

from __future__ import annotations

import numpy as np
import pytest

from pinflex.checks import check_n_modes, check_q, check_y
from pinflex.erls import assembly, kinematics
from pinflex.erls.joints import full_shapes, joint_transform
from pinflex.erls.model import MOVED, PUBLIC, FlexibleModel
from pinflex.exceptions import ConfigurationError, DesignVariableOutOfBounds, ImmutableModelError


def _public(obj) -> set[str]:
    names = set(vars(type(obj))) | set(vars(obj))
    return {n for n in names if not n.startswith("_")}


def test_flexible_model_shows_exactly_its_public_names(two_link_planar):
    """Class and instance attributes without an underscore are PUBLIC, and all of PUBLIC exists."""
    assert _public(two_link_planar) == set(PUBLIC)
    assert len(PUBLIC) == len(set(PUBLIC))
    assert [n for n in dir(two_link_planar) if not n.startswith("_")] == sorted(PUBLIC)
    assert "__dir__" not in vars(FlexibleModel)  # no trick: dir() is object's own


def test_former_methods_name_their_new_place(two_link_planar):
    """An old call raises an AttributeError saying where the function lives now."""
    for name, where in MOVED.items():
        assert not hasattr(two_link_planar, name)
        with pytest.raises(AttributeError) as info:
            getattr(two_link_planar, name)
        assert where in str(info.value)
    with pytest.raises(ImmutableModelError, match="with_values"):
        two_link_planar.set_value("m1", 0.2)
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        two_link_planar.nonsense  # noqa: B018


def test_free_functions_give_the_public_routes_numbers(two_link_planar):
    """check_q/check_y, pose_terms + matrices_from_terms and the joint map as the model's own."""
    arm = two_link_planar
    q = np.array([0.3, -0.7])
    np.testing.assert_array_equal(check_q(arm, q), q)
    with pytest.raises(ConfigurationError, match="expected 2 joint values"):
        check_q(arm, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(check_y(arm, None), arm.y0)
    if arm.ny:
        d = arm.design[0]
        with pytest.raises(DesignVariableOutOfBounds):
            check_y(arm, np.full(arm.ny, d.upper + 1.0))
    assert check_n_modes(arm, 10**6) == arm.n_elastic
    M, K = arm.matrices(q)
    M2, K2 = assembly.matrices_from_terms(arm, kinematics.pose_terms(arm, q[None]),
                                          check_y(arm, None), 1)
    np.testing.assert_allclose(M2[0], M, rtol=0, atol=1e-14 * np.abs(M).max())
    np.testing.assert_allclose(K2[0], K, rtol=0, atol=1e-14 * np.abs(K).max())
    one = kinematics.pose_terms_one(arm, q)
    batch = kinematics.pose_terms(arm, q[None])
    for link in batch.jac:
        np.testing.assert_allclose(one.jac[link], batch.jac[link], atol=1e-14)
    terms, placements = kinematics.pose_terms_and_placements(arm, q)
    for link, p in arm.node_placements(q).items():
        np.testing.assert_allclose(placements[link].positions_m, p.positions_m, atol=1e-14)
    T = joint_transform(arm, q)
    np.testing.assert_array_equal(T, arm.joint_transform(q))
    shapes = arm.modes(q, n_modes=2).shapes
    np.testing.assert_allclose(full_shapes(arm, q, shapes), T @ shapes, atol=1e-14)


def test_taylor_model_shows_its_documented_fields_and_queries(two_link_planar):
    """A TaylorModel's public names are its documented fields and queries; caches are private."""
    from pinflex import expand

    tm = expand(two_link_planar, [1.817, 5.312], order=2, modes=(1,))
    documented = {"space", "q0", "y0", "modes", "joint_idx", "design_idx", "eigval_jets",
                  "radius", "spectrum", "spectrum_slopes", "freq_jets", "joints", "order_choice",
                  "order", "jet", "offsets", "error_estimate", "check_radius", "evaluate",
                  "coefficients", "design_vars", "linear_parts"}
    assert _public(tm) == documented
    np.testing.assert_array_equal(tm.coefficients("eigval"), tm.jet("eigval").reshape(
        tm.space.ncoef, -1))
