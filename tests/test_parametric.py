"""Taylor coefficients of M, K and eigenvalues against finite differences and exact solves."""

import warnings

import numpy as np
import pinocchio as pin
import pytest
from arms import PRISMATIC
from conftest import TWO_LINK, single_link_urdf

from pinflex import jets
from pinflex.description import parse
from pinflex.erls import FlexibleModel, kinematics
from pinflex.exceptions import RepeatedEigenvalue, TaylorRadiusWarning
from pinflex.parametric import expand, matrix_jets, pose_jets

Q0 = np.array([1.817, 5.312])




def _unit(space, k):
    return space.index[tuple(int(i == k) for i in range(space.nvars))]


def _fd(f, x0, k, h):
    """Fourth-order central difference of f along coordinate k."""
    e = np.zeros_like(x0)
    e[k] = h
    return (-f(x0 + 2 * e) + 8 * f(x0 + e) - 8 * f(x0 - e) + f(x0 - 2 * e)) / (12 * h)


@pytest.mark.parametrize("urdf,planar", [(TWO_LINK, True), (TWO_LINK, False), ("prismatic", False)])
def test_matrix_jets_match_finite_differences(urdf, planar):
    """First and mixed second Taylor coefficients of M and K equal finite differences."""
    model = FlexibleModel(parse(PRISMATIC) if urdf == "prismatic" else urdf, planar=planar)
    rng = np.random.default_rng(4)
    q0 = rng.uniform(-1, 1, model.nv)
    y0 = model.y0
    space, M, K, jidx, didx = matrix_jets(model, q0, y0, order=3)
    x0 = np.concatenate([q0, y0])
    np.testing.assert_allclose(M[0], model.matrices(q0, y0)[0], atol=1e-14)

    def mats(x):
        Mx, Kx = model.matrices(x[: model.nv], x[model.nv :], check_bounds=False)
        return np.concatenate([Mx.ravel(), Kx.ravel()])

    scale = np.abs(mats(x0)).max()
    for k in range(space.nvars):
        fd = _fd(mats, x0, k, 1e-3)
        jet = np.concatenate([M[_unit(space, k)].ravel(), K[_unit(space, k)].ravel()])
        assert np.abs(fd - jet).max() < 1e-8 * scale
    # mixed second derivative d²/dq0 dq1 = coefficient of δq0 δq1
    alpha = tuple(1 if i in (0, 1) else 0 for i in range(space.nvars))

    def d1(x):
        return _fd(mats, x, 1, 1e-3)

    fd2 = _fd(d1, x0, 0, 1e-3)
    jet2 = np.concatenate([M[space.index[alpha]].ravel(), K[space.index[alpha]].ravel()])
    assert np.abs(fd2 - jet2).max() < 1e-6 * scale


def test_jacobian_jets_start_at_pinocchio_jacobians():
    """The constant coefficient of every link Jacobian jet is Pinocchio's LOCAL Jacobian."""
    model = FlexibleModel(parse(PRISMATIC))
    q0 = np.array([0.3, -0.7, 1.1])
    space = jets.JetSpace(3, 2)
    terms = pose_jets(model, space, q0, {0: 0, 1: 1, 2: 2})
    ref = kinematics.pose_terms(model, q0[None])
    for link, jet in terms.jac.items():
        np.testing.assert_allclose(jet[0], ref.jac[link][0], atol=1e-14)


def test_eigenvalue_jets_match_finite_differences_of_exact_eigenvalues():
    """λ₁ Taylor coefficients (first and second order) equal differences of exact solves."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, Q0, order=4, modes=(1, 2))
    x0 = np.concatenate([Q0, model.y0])

    def lam(x):
        return (2 * np.pi * model.frequencies(x[:2], x[2:], check_bounds=False)[:2]) ** 2

    sp = tm.space
    for k in range(4):
        np.testing.assert_allclose(tm.eigval_jets[_unit(sp, k)], _fd(lam, x0, k, 1e-4),
                                   rtol=1e-7, atol=1e-6 * abs(lam(x0)[0]))
    alpha = (0, 1, 1, 0)  # δq2 δm1
    fd2 = _fd(lambda x: _fd(lam, x, 2, 1e-3), x0, 1, 1e-3)
    np.testing.assert_allclose(tm.eigval_jets[sp.index[alpha]], fd2, rtol=1e-5)


def test_taylor_error_falls_with_order_at_small_offsets():
    """At a small offset the error of λ^p falls like |δ|^(p+1): each order gains ~decades."""
    model = FlexibleModel(TWO_LINK, planar=True)
    q = Q0 + np.array([0.0, 0.05])
    y = np.array([0.14, 0.11])
    exact = (2 * np.pi * model.frequencies(q, y)[0]) ** 2
    errors = [abs(expand(model, Q0, order=p).evaluate(q[None], y[None])[0, 0] / exact - 1)
              for p in (1, 2, 3, 4, 5)]
    assert all(b < a / 5 for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 1e-8


def test_only_requested_variables_are_expanded():
    """Expanding one joint and one mass gives a 2-variable model equal to the full one there."""
    model = FlexibleModel(TWO_LINK, planar=True)
    small = expand(model, Q0, order=4, joints=["q2"], design=["m1"])
    full = expand(model, Q0, order=4)
    assert small.space.nvars == 2
    Q = np.column_stack([np.full(5, Q0[0]), Q0[1] + np.linspace(-0.1, 0.1, 5)])
    Y = np.column_stack([np.linspace(0, 0.25, 5), np.full(5, model.y0[1])])
    np.testing.assert_allclose(small.evaluate(Q, Y), full.evaluate(Q, Y), rtol=1e-13)


def test_partially_linear_model_is_linear_in_design_and_matches_l_polynomials():
    """λ̂ is affine in y and equals l0 + Σ l_j δy_j (eq. 9)."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, Q0, order=4)
    Q = Q0 + np.array([[0.0, 0.1], [0.05, -0.05]])
    y_a, y_b = np.array([0.0, 0.0]), np.array([0.25, 0.25])
    fa = tm.evaluate(Q, y_a, linear_in_design=True)
    fb = tm.evaluate(Q, y_b, linear_in_design=True)
    fm = tm.evaluate(Q, 0.5 * (y_a + y_b), linear_in_design=True)
    np.testing.assert_allclose(fm, 0.5 * (fa + fb), rtol=1e-13)
    l0, L = tm.linear_parts(Q)
    np.testing.assert_allclose(l0 + L @ (y_b - tm.y0), fb, rtol=1e-13)


def test_double_eigenvalue_at_expansion_point_raises_named_error():
    """A circular bar has equal bending frequencies in two planes: the recursion refuses it."""
    extra = ('<pinflex:point_mass name="tip" link="bar" xyz="1 0 0" mass="0.1" design="true" '
             'lower="0" upper="1"/>')
    xml = single_link_urdf("fixed", elements=6, Iy=1e-9, Iz=1e-9, J=2e-9, extra=extra)
    model = FlexibleModel(parse(xml))
    with pytest.raises(RepeatedEigenvalue) as err:
        expand(model, np.zeros(0), order=2, modes=(1,), design=["tip"])
    assert len(err.value.cluster) == 2
    # the planar model of the same bar has a simple first mode and works
    planar = FlexibleModel(parse(xml), planar=True)
    tm = expand(planar, np.zeros(0), order=2, design=["tip"])
    assert tm.eigval_jets.shape == (3, 1)


def test_evaluating_far_beyond_the_radius_warns():
    """Evaluating two radians away along the elbow warns with TaylorRadiusWarning."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, Q0, order=6, joints=["q2"], design=[])
    with pytest.warns(TaylorRadiusWarning):
        tm.evaluate(np.array([[Q0[0], Q0[1] + 2.0]]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tm.evaluate(np.array([[Q0[0], Q0[1] + 0.1]]))
    # and the polynomial is indeed useless there
    exact = (2 * np.pi * model.frequencies([Q0[0], Q0[1] + 2.0])[0]) ** 2
    far = tm.evaluate(np.array([[Q0[0], Q0[1] + 2.0]]), warn=False)[0, 0]
    assert abs(far / exact - 1) > 0.1


def test_frequency_polynomial_is_the_square_root_of_the_eigenvalue_one():
    """The Hz jet evaluates to √λ/2π of the λ jet to truncation order."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, Q0, order=6)
    q = Q0 + np.array([0.0, 0.01])
    f = tm.evaluate(q[None], quantity="freq_hz")[0, 0]
    lam = tm.evaluate(q[None])[0, 0]
    assert f == pytest.approx(np.sqrt(lam) / (2 * np.pi), rel=1e-11)
    assert pin is not None


def test_expansion_along_a_trajectory_meets_the_tolerance_with_the_fewest_points():
    """Covering benchmark A's path to 1e-4: every sample within tol, fewest points chosen."""
    from pinflex.assignment.study import user_trajectory
    from pinflex.parametric import expand_along

    model = FlexibleModel(TWO_LINK, planar=True)
    traj = user_trajectory(model, "benchmark_a")
    cover = expand_along(model, traj.q, np.zeros(2), tol=1e-4, orders=(1, 2, 3, 4))
    exact = model.frequencies(traj.q, np.zeros(2), n_modes=1)[:, 0]
    approx = cover.evaluate(traj.q)[:, 0]
    assert np.max(np.abs(approx / exact - 1)) <= 1e-4
    assert len(cover.models) == min(cover.candidates.values())
    assert cover.candidates[1] > cover.candidates[4]  # low orders need more points
    # segments tile the samples without gaps
    assert cover.segments[0][0] == 0 and cover.segments[-1][1] == 152
    assert all(a[1] == b[0] for a, b in zip(cover.segments, cover.segments[1:]))


def test_sampled_model_equals_the_full_polynomial_for_any_design():
    """Fixing the joint samples changes nothing: values equal evaluate() at any design."""
    from pinflex.assignment.study import user_trajectory
    from pinflex.parametric import sample

    model = FlexibleModel(TWO_LINK, planar=True)
    traj = user_trajectory(model, "benchmark_a")
    tm = expand(model, Q0, order=4, modes=(1, 2))
    for lin in (False, True):
        s = sample(tm, traj.q, linear_in_design=lin)
        for y in ([0.0, 0.0], [0.2, 0.05], [0.25, 0.25]):
            np.testing.assert_allclose(
                s.values(np.array(y)),
                tm.evaluate(traj.q, np.array(y), quantity="freq_hz", linear_in_design=lin),
                rtol=1e-13,
            )


def test_taylor_model_is_read_only_and_keeps_no_hidden_caches():
    """Arrays of a Taylor model cannot be written; evaluating it adds no state to it."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, Q0, order=3)
    for array in (tm.eigval_jets, tm.freq_jets, tm.q0, tm.y0, tm.radius,
                  tm.coefficients("freq_hz", linear_in_design=True)):
        with pytest.raises(ValueError):
            array[...] = 0.0
    before = dict(vars(tm))
    first = tm.evaluate(Q0[None] + 0.01, quantity="freq_hz")
    assert tm.evaluate(Q0[None] + 0.01, quantity="freq_hz") == pytest.approx(first, rel=0)
    assert set(vars(tm)) == set(before)
