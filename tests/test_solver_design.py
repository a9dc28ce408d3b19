"""Section, material and joint-stiffness variables on the solver-coordinate jet route.

References: the nodal-coordinate assembly (:func:`pinflex.parametric.matrix_jets`, a second
formulation of the same pencil), and the exact model's frequencies (nodal pencil, no jets).
"""

import numpy as np
import pytest
import scipy.linalg as sla
from arms import two_link
from conftest import ROOT

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.parametric import expand, matrix_jets, solver_design
from pinflex.parametric.conditioned import embed, reduced_solver_jets
from pinflex.parametric.eigen import eigen_jets

QU = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
QA = np.array([1.817, 5.312])


def _nodal(model, q0, y0, order, design, modes):
    space, M, K, _, _ = matrix_jets(model, q0, y0, order=order, design=design)
    w, V = sla.eigh(K[0], M[0])
    idx = [model.n_rigid + m - 1 for m in modes]
    return eigen_jets(space, M, K, idx, eigvals0=w, eigvecs0=V)[0]


def _worst(a, b, space):
    """Largest coefficient difference, relative to the largest coefficient of its degree."""
    out = 0.0
    for d in range(space.order + 1):
        s = space.degree_slice(d)
        out = max(out, float(np.max(np.abs(a[s] - b[s]) / np.abs(b[s]).max(axis=0))))
    return out


def _ur5_sprung(tmp_path):
    """The tube UR5 with a design spring on the elbow and a fixed one on wrist 1."""
    text = (ROOT / "urdf" / "ur5_tubes.xml").read_text()
    text = text.replace(
        '<pinflex:parameter name="payload"',
        '<pinflex:parameter name="k_elbow" value="1e5" lower="1e4" upper="1e6" design="true"/>'
        '\n  <pinflex:parameter name="payload"')
    text = text.replace(
        "</pinflex:overlay>",
        '<pinflex:joint name="elbow_joint" stiffness="{k_elbow}"/>'
        '<pinflex:joint name="wrist_1_joint" stiffness="3e4"/></pinflex:overlay>')
    path = tmp_path / "ur5_sprung.xml"
    path.write_text(text)
    return FlexibleModel(path, joints="annotated", values={"payload": 2.0})


def _bench_designed():
    """Benchmark A's geometry (absolute angles): rod d1, tube d2, material E, spring k2."""
    text = two_link(
        'shape="solid_circle" diameter="{d1}"',
        'shape="hollow_circle" outer_diameter="{d2}" wall="0.002"',
        params='<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="E" value="69e9" lower="50e9" upper="80e9" '
        'design="true"/><pinflex:parameter name="k2" value="2000" lower="500" upper="1e4" '
        'design="true"/>',
        material='E="{E}" density="2687"',
        extra='<pinflex:point_mass name="m2" link="link2" xyz="0.45 0 0" mass="0.125"/>',
        joints='<pinflex:joint name="q2" stiffness="{k2}"/>')
    return FlexibleModel(parse(text), planar=True, joints="annotated")


def test_ur5_tube_variables_equal_the_nodal_route(tmp_path):
    """UR5, p = 3, 6 joints + all four tube dimensions: λ coefficients of modes 1-3.

    With the URDF inertia the tube links keep (6.9 kg of motors at 0.3 m on the upper arm)
    the nodal route's coefficients move by up to ~2e-9 (relative to their degree's largest)
    when its mass entries are perturbed by 1e-16 relative, so the routes agree to that
    rounding; with the tubes alone (``inertia="beam-only"``) to 1e-10.
    """
    path = ROOT / "urdf" / "ur5_tubes.xml"
    bare = tmp_path / "ur5_beam_only.xml"
    bare.write_text(path.read_text().replace("<pinflex:flexible ",
                                             '<pinflex:flexible inertia="beam-only" '))
    for file, tol in ((path, 5e-9), (bare, 1e-10)):
        model = FlexibleModel(file, values={"payload": 2.0})
        assert bool(model.description.bodies) == (file == path)
        assert solver_design.covered(model)
        tm = expand(model, QU, order=3, modes=(1, 2, 3))
        assert tm.space.nvars == 10
        assert _worst(tm.eigval_jets, _nodal(model, QU, None, 3, None, (1, 2, 3)),
                      tm.space) < tol


def test_benchmark_geometry_section_material_and_spring_variables_equal_the_nodal_route():
    """Rod and tube diameters, Young's modulus and a joint stiffness, at and off nominal."""
    model = _bench_designed()
    assert model.n_rigid == 1 and model.design_names == ("d1", "d2", "E", "k2")
    for y in (None, model.y0 * np.array([1.1, 0.9, 1.05, 1.5])):
        tm = expand(model, QA, y, order=4, modes=(1, 2))
        assert _worst(tm.eigval_jets, _nodal(model, QA, y, 4, None, (1, 2)), tm.space) < 1e-10


def test_ur5_spring_variable_equals_the_nodal_route_within_its_rounding(tmp_path):
    """UR5 with a design elbow spring: agreement at the nodal route's own rounding level.

    The nodal-coordinate coefficients of this model (with the URDF inertia its tube links
    keep) move by up to ~2e-9 (relative to their degree's largest) when its matrix entries
    are perturbed by 1e-16 relative; those of the solver route by < 1e-12 (checked here): the
    difference between the routes is the nodal route's rounding.
    """
    model = _ur5_sprung(tmp_path)
    assert model.n_rigid == 4
    design = ["D_upper", "k_elbow"]
    tm = expand(model, QU, order=3, modes=(1, 2, 3), design=design)
    assert _worst(tm.eigval_jets, _nodal(model, QU, None, 3, design, (1, 2, 3)), tm.space) < 5e-9
    full, space, keep, M, K, _, _ = reduced_solver_jets(model, QU, order=3, design=design)
    assert K.ndim == 3 and np.any(K[1:])
    rng = np.random.default_rng(5)
    idx = [model.n_rigid + k for k in range(3)]
    for _ in range(2):
        E = rng.uniform(-1e-16, 1e-16, M.shape)
        Mp = M * (1.0 + E + np.swapaxes(E, -1, -2))
        w, V = solver_design.expansion_eigenpairs(model, K[0], Mp[0])
        lam = embed(full, space, keep, eigen_jets(space, Mp, K, idx, eigvals0=w,
                                                 eigvecs0=V)[0])
        assert _worst(lam, tm.eigval_jets, full) < 1e-12


def test_sprung_tube_arm_taylor_error_falls_like_h_to_the_p_plus_one():
    """Against the exact frequencies (nodal pencil, no jets): order-3 error falls like h⁴."""
    model = _bench_designed()
    tm = expand(model, QA, order=3, modes=(1, 2))
    direction = np.array([0.6, -1.0, 0.01, -0.008, 3e9, 400.0])  # q1, q2, d1, d2, E, k2
    errs = []
    for h in (0.1, 0.05):
        step = h * direction
        q, y = QA + step[:2], model.y0 + step[2:]
        exact = (2 * np.pi * model.frequencies(q, y, n_modes=2)) ** 2
        errs.append(np.max(np.abs(tm.evaluate(q[None], y, warn=False)[0] / exact - 1)))
    assert errs[0] < 1e-3
    assert 10 < errs[0] / errs[1] < 22, errs  # 2⁴ = 16


def test_stiffness_jet_has_no_pose_terms_for_section_variables():
    """Sections change K only on pure-design coefficients; the blocks sum to the nominal."""
    model = FlexibleModel(ROOT / "urdf" / "ur5_tubes.xml", values={"payload": 2.0})
    full, space, keep, M, K, _, _ = reduced_solver_jets(model, QU, order=3,
                                                        design=["D_upper", "t_fore"])
    nj = space.nvars - 2
    joint_deg = space.multi_indices[:, :nj].sum(axis=1)
    assert np.all(K[joint_deg > 0] == 0.0)
    assert np.any(K[(joint_deg == 0) & (space.degrees > 0)])
    np.testing.assert_array_equal(K[0][: model.nx, : model.nx], np.eye(model.nx))
    from pinflex.erls import design as erls_design
    from pinflex.erls import solve

    names = list(model.design_names)
    f0 = erls_design.channel_values(model, lambda n: model.y0[names.index(n)])
    blocks = solver_design.link_blocks(model)
    for link, core in solve.solve_plan(model).cores.items():
        chans = [(n, f) for n, (ch, f) in enumerate(zip(model.plan.design.channels, f0))
                 if ch.owner == link]
        H = sum(f * blocks[n][0] for n, f in chans if model.plan.design.channels[n].kind == "M")
        np.testing.assert_allclose(H, core.H_oo, rtol=1e-12, atol=1e-12 * np.abs(H).max())
        Kh = sum(f * blocks[n] for n, f in chans if model.plan.design.channels[n].kind == "K")
        np.testing.assert_allclose(Kh, np.eye(Kh.shape[0]), atol=1e-12)


def test_locked_and_sprung_joints_with_tube_variables_equal_the_nodal_route():
    """Locked joints on the solver route, with section variables.

    Benchmark geometry with q2 locked (at and off the nominal design), and the UR5 tubes with
    the elbow locked and a wrist spring.
    """
    model = FlexibleModel(_bench_designed().description, planar=True, joints={"q2": "locked"})
    assert model.n_rigid == 1 and model.ndof == model.nx + 1
    for y in (None, model.y0 * np.array([1.1, 0.9, 1.05, 1.0])):
        tm = expand(model, QA, y, order=4, modes=(1, 2), design=["d1", "d2", "E"])
        ref = _nodal(model, QA, y, 4, ["d1", "d2", "E"], (1, 2))
        assert _worst(tm.eigval_jets, ref, tm.space) < 1e-10
    model = FlexibleModel(ROOT / "urdf" / "ur5_tubes.xml", values={"payload": 2.0},
                          joints={"elbow_joint": "locked", "wrist_2_joint": 3e4})
    assert solver_design.covered(model) and model.n_rigid == 4
    design = ["D_upper", "D_fore"]
    tm = expand(model, QU, order=3, modes=(1, 2, 3), design=design)
    assert _worst(tm.eigval_jets, _nodal(model, QU, None, 3, design, (1, 2, 3)), tm.space) < 1e-10


@pytest.mark.parametrize("factor", [1.0, 1.15])
def test_expansion_eigenpairs_solve_the_pencil(factor):
    """The inverse-form eigenpairs at a point: K φ = λ M φ, φᵀ M φ = 1, free modes first."""
    model = _bench_designed()
    y = model.y0 * factor
    full, space, keep, M, K, _, _ = reduced_solver_jets(model, QA, y, order=1)
    w, V = solver_design.expansion_eigenpairs(model, K[0], M[0])
    assert np.all(np.diff(w) >= 0) and w[0] == 0.0 and w[1] > 0
    from pinflex.erls.eigensolve import rounding_bound

    R = K[0] @ V[:, 1:] - M[0] @ V[:, 1:] * w[1:]
    rel = np.abs(R).max(axis=0) / (w[1:] * np.abs(M[0] @ V[:, 1:]).max(axis=0))
    assert np.all(rel < rounding_bound(w[1:]))  # the inverse form's stated accuracy
    np.testing.assert_allclose(V[:, :11].T @ M[0] @ V[:, :11], np.eye(11), atol=1e-11)
    assert np.max(np.abs(K[0] @ V[:, 0])) < 1e-9 * np.abs(K[0]).max()  # the free joint
    ref = sla.eigh(K[0], M[0], eigvals_only=True)
    np.testing.assert_allclose(w[1:4], ref[1:4], rtol=1e-9)


def _along(tm, rays):
    """Coefficients in t (order p) of λ(x0 + δx(t)), ``rays[v]`` the series of δx_v in t."""
    p = tm.space.order
    out = np.zeros((p + 1, tm.eigval_jets.shape[1]))
    for alpha, coef in zip(tm.space.multi_indices, tm.eigval_jets):
        ser = np.zeros(p + 1)
        ser[0] = 1.0
        for v, power in enumerate(alpha):
            for _ in range(power):
                ser = np.convolve(ser, rays[v])[: p + 1]
        out += ser[:, None] * coef[None, :]
    return out


def _ray(p, *coefs):
    out = np.zeros(p + 1)
    out[1 : 1 + len(coefs)] = coefs
    return out


_ROD = """<robot name="sprung_rod" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="rod"/>
  <joint name="q" type="revolute"><parent link="base"/><child link="rod"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:parameter name="d" value="0.02" lower="0.01" upper="0.04" design="true"/>
  <pinflex:parameter name="k" value="800" lower="100" upper="1e5" design="true"/>
  <pinflex:flexible link="rod" elements="8" tip="0.8 0 0" normal="0 0 1">
    <pinflex:material E="7e10" poisson="0.33" density="2700"/>
    <pinflex:section shape="solid_circle" diameter="{d}"/>
  </pinflex:flexible>
  <pinflex:joint name="q" stiffness="{k}"/>
</robot>"""


def test_sprung_rod_follows_the_exact_scaling_of_diameter_and_stiffness():
    """λ(d s, k s⁴) = s² λ(d, k) for a straight rod on a root spring (bending modes, planar).

    Bending stiffness ∝ d⁴, the spring ∝ s⁴, every mass ∝ d² (no rotary inertia in planar
    bending, no other mass): an exact law of the discrete model, so along the curve
    d = d0 (1 + t), k = k0 (1 + t)⁴ the coefficients in t are λ0 (1, 2, 1, 0, 0) exactly. It
    checks the mixed section-spring coefficients up to order 4 without any reference solver.
    """
    model = FlexibleModel(parse(_ROD), planar=True, joints="annotated")
    assert model.n_rigid == 0
    tm = expand(model, [0.0], order=4, modes=(1, 2, 3), joints=[])
    d0, k0 = model.y0
    got = _along(tm, [_ray(4, d0), _ray(4, 4 * k0, 6 * k0, 4 * k0, k0)])
    want = np.outer([1.0, 2.0, 1.0, 0.0, 0.0], tm.eigval_jets[0])
    assert np.max(np.abs(got - want) / tm.eigval_jets[0]) < 1e-10


def test_two_link_arm_follows_the_exact_scaling_of_modulus_density_and_stiffness():
    """Along a pose ray: λ(q(t), E s, k s) = s λ(q(t)) and λ(q(t), ρ s) = λ(q(t)) / s.

    Benchmark A's geometry with beams only (no other mass), both diameters, E, ρ and the q2
    spring as design variables: stiffness is ∝ E and k, mass ∝ ρ, exactly, at every pose. With
    q = q0 + a t and s = 1 + t the series in t of the full expansion must equal (1 + t) (resp.
    1/(1 + t)) times the series of the joint-only terms: the mixed joint-design coefficients to
    order 4, against an identity of the discrete model.
    """
    text = two_link(
        'shape="solid_circle" diameter="{d1}"',
        'shape="hollow_circle" outer_diameter="{d2}" wall="0.002"',
        params='<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="E" value="69e9" lower="5e10" upper="8e10" '
        'design="true"/><pinflex:parameter name="rho" value="2687" lower="1e3" upper="9e3" '
        'design="true"/><pinflex:parameter name="k2" value="2000" lower="500" upper="1e4" '
        'design="true"/>',
        material='E="{E}" poisson="0.3" density="{rho}"',
        joints='<pinflex:joint name="q2" stiffness="{k2}"/>')
    model = FlexibleModel(parse(text), planar=True, joints="annotated")
    tm = expand(model, QA, order=4, modes=(1, 2))
    _, _, E0, rho0, k0 = model.y0
    a = (_ray(4, 0.3), _ray(4, -0.5))
    z = np.zeros(5)
    pose_only = _along(tm, [*a, z, z, z, z, z])
    for rays, factor in (([*a, z, z, _ray(4, E0), z, _ray(4, k0)], [1, 1, 0, 0, 0]),
                         ([*a, z, z, z, _ray(4, rho0), z], [1, -1, 1, -1, 1])):
        got = _along(tm, rays)
        want = np.stack([np.convolve(factor, pose_only[:, j])[:5] for j in range(2)], axis=1)
        assert np.max(np.abs(got - want) / tm.eigval_jets[0]) < 1e-10
