"""Parameters, ``{name}`` references and section/material/spring design variables."""

import math

import numpy as np
import pytest
from arms import two_link
from reference_fe import planar_two_link_frequencies

import pinflex
from pinflex.checks import check_y
from pinflex.description import parse
from pinflex.erls import BatchAlgebra, FlexibleModel, assembly, kinematics
from pinflex.erls import design as erls_design
from pinflex.exceptions import (
    DesignVariableNotFound,
    DesignVariableOutOfBounds,
    ImmutableModelError,
    InvalidBeamProperty,
    InvalidDescription,
    ParameterNotFound,
)
from pinflex.parametric import matrix_jets

Q0 = np.array([1.817, 5.312])


TUBES = two_link(
    'shape="hollow_circle" outer_diameter="{d1}" wall="{t1}"',
    'shape="hollow_circle" outer_diameter="{d2}" wall="0.002"',
    params='<pinflex:parameter name="d1" value="0.04" lower="0.02" upper="0.06" design="true"/>'
    '<pinflex:parameter name="t1" value="0.003" lower="0.001" upper="0.008" design="true"/>'
    '<pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.05" design="true"/>'
    '<pinflex:parameter name="mp" value="0.2" lower="0" upper="1" design="true"/>',
    extra='<pinflex:point_mass name="tip" link="link2" xyz="0.45 0 0" mass="{mp}"/>',
)


def _literal(d1, t1, d2, mp):
    return two_link(
        f'shape="hollow_circle" outer_diameter="{d1!r}" wall="{t1!r}"',
        f'shape="hollow_circle" outer_diameter="{d2!r}" wall="0.002"',
        extra=f'<pinflex:point_mass name="tip" link="link2" xyz="0.45 0 0" mass="{mp!r}"/>',
    )


def _tube(D, t):
    """Textbook thin-walled-or-not tube: A, I (written here, not taken from pinflex)."""
    d = D - 2 * t
    return math.pi * (D**2 - d**2) / 4, math.pi * (D**4 - d**4) / 64


def test_references_and_values_equal_literal_numbers():
    """A file with {refs} equals the same file with the numbers written in."""
    ref = FlexibleModel(parse(TUBES), planar=True)
    lit = FlexibleModel(parse(_literal(0.04, 0.003, 0.03, 0.2)), planar=True)
    # the literal file has no design parameters, so it is solved in relative coordinates
    # (pinflex.erls.solve) and the referencing one in nodal coordinates: round-off differs
    np.testing.assert_allclose(ref.frequencies(Q0), lit.frequencies(Q0), rtol=1e-11)
    moved = FlexibleModel(parse(TUBES), planar=True, values={"d1": 0.05, "mp": 0.4})
    lit2 = FlexibleModel(parse(_literal(0.05, 0.003, 0.03, 0.4)), planar=True)
    np.testing.assert_allclose(moved.frequencies(Q0), lit2.frequencies(Q0), rtol=1e-11)
    assert moved.design_names == ("d1", "t1", "d2", "mp")
    assert [d.kind for d in moved.design] == ["parameter"] * 4
    np.testing.assert_allclose(moved.y0, [0.05, 0.003, 0.03, 0.4])


@pytest.mark.parametrize("seed", [0, 1])
def test_design_vector_equals_rebuilt_model_and_global_fe(seed):
    """M(y) from the channel decomposition = a model rebuilt at y = the global FE."""
    model = FlexibleModel(parse(TUBES), planar=True)
    rng = np.random.default_rng(seed)
    lo = np.array([d.lower for d in model.design])
    hi = np.array([d.upper for d in model.design])
    for _ in range(3):
        y = lo + rng.uniform(0.05, 0.95, 4) * (hi - lo)
        q = rng.uniform(-np.pi, np.pi, 2)
        ours = model.frequencies(q, y)
        rebuilt = FlexibleModel(parse(TUBES), planar=True, values=dict(zip(model.design_names, y)))
        np.testing.assert_allclose(ours, rebuilt.frequencies(q), rtol=1e-11)
        # independent: the planar global frame with textbook tube formulas (per-link EI)
        A1, I1 = _tube(y[0], y[1])
        A2, I2 = _tube(y[2], 0.002)
        from reference_fe import planar_chain_matrices, solve_frequencies

        K, M = planar_chain_matrices(q, [0.6, 0.45], [4, 3], EI=[69e9 * I1, 69e9 * I2],
                                     rhoA=[2687 * A1, 2687 * A2], EA=[69e9 * A1, 69e9 * A2],
                                     end_masses=[0.0, y[3]])
        _, f_ref = solve_frequencies(K, M, n_rigid=2)
        np.testing.assert_allclose(ours, f_ref, rtol=1e-9)


@pytest.mark.parametrize(
    ("section", "material", "params", "values"),
    [
        ('shape="solid_circle" diameter="{d}"', 'E="69e9" density="2687"',
         '<pinflex:parameter name="d" value="0.03" lower="0.02" upper="0.05" design="true"/>',
         {"d": 0.037}),
        ('shape="rectangle" width="{b}" height="{h}"', 'E="2.1e11" density="7850"',
         '<pinflex:parameter name="b" value="0.02" lower="0.01" upper="0.04" design="true"/>'
         '<pinflex:parameter name="h" value="0.03" lower="0.01" upper="0.05" design="true"/>',
         {"b": 0.025, "h": 0.02}),
        ('A="7.07e-4" Iy="{i}" Iz="{i}" J="7.94e-8"', 'E="{E}" linear_density="{mu}"',
         '<pinflex:parameter name="i" value="3.97e-8" lower="1e-8" upper="1e-7" design="true"/>'
         '<pinflex:parameter name="E" value="69e9" lower="5e10" upper="2.2e11" design="true"/>'
         '<pinflex:parameter name="mu" value="1.9" lower="1" upper="5" design="true"/>',
         {"i": 5e-8, "E": 1.1e11, "mu": 2.6}),
        ('shape="hollow_circle" outer_diameter="{D}" inner_diameter="{di}"',
         'E="69e9" G="{G}" density="{rho}"',
         '<pinflex:parameter name="D" value="0.05" lower="0.03" upper="0.08" design="true"/>'
         '<pinflex:parameter name="di" value="0.04" lower="0.0" upper="0.07" design="true"/>'
         '<pinflex:parameter name="G" value="26e9" lower="2e10" upper="3e10" design="true"/>'
         '<pinflex:parameter name="rho" value="2700" lower="1000" upper="8000" design="true"/>',
         {"D": 0.06, "di": 0.03, "G": 2.2e10, "rho": 7000.0}),
    ],
)
def test_every_kind_of_design_parameter_moves_the_model_exactly(section, material, params,
                                                                values):
    """Solid, hollow (inner diameter), rectangle, explicit I, E, G, ρ, μ: spatial model."""
    text = two_link(section, section, params=params, material=material)
    model = FlexibleModel(parse(text))
    y = check_y(model, values)
    rebuilt = FlexibleModel(parse(text), values=values)
    np.testing.assert_allclose(model.frequencies(Q0, y), rebuilt.frequencies(Q0), rtol=1e-9)
    assert not np.allclose(model.frequencies(Q0, y), model.frequencies(Q0), rtol=1e-4)


def test_joint_stiffness_parameter_is_a_design_variable():
    """stiffness="{k}" on an annotated joint: y moves the spring (global FE with a spring)."""
    text = two_link('A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"',
                    'A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"',
                    material='E="69e9" linear_density="1.9"',
                    params='<pinflex:parameter name="k" value="2000" lower="100" upper="1e5" '
                    'design="true"/>', joints='<pinflex:joint name="q2" stiffness="{k}"/>')
    model = FlexibleModel(parse(text), planar=True, joints="annotated")
    assert model.design_names == ("k",) and model.n_rigid == 1
    _, f_ref = planar_two_link_frequencies(Q0, 0.0, 0.0, joints=[None, 7000.0])
    np.testing.assert_allclose(model.frequencies(Q0, [7000.0]), f_ref, rtol=1e-9)


def test_parameter_errors_are_named():
    """Unknown/unresolved names, bounds, invalid sections, design parameters in geometry."""
    with pytest.raises(ParameterNotFound, match="nope"):
        parse(two_link('shape="solid_circle" diameter="{nope}"',
                       'shape="solid_circle" diameter="0.03"'))
    with pytest.raises(InvalidDescription, match="reference"):
        parse(two_link('shape="solid_circle" diameter="{d"',
                       'shape="solid_circle" diameter="0.03"',
                       params='<pinflex:parameter name="d" value="0.03"/>'))
    with pytest.raises(DesignVariableOutOfBounds):
        FlexibleModel(parse(TUBES), values={"d1": 0.07})
    with pytest.raises(DesignVariableNotFound):
        FlexibleModel(parse(TUBES), values={"d9": 0.03})
    model = FlexibleModel(parse(TUBES), planar=True)
    with pytest.raises(ImmutableModelError, match="with_values"):
        model.set_value("d1", 0.03)
    with pytest.raises(InvalidBeamProperty, match="inner diameter"):  # wall above D/2
        model.frequencies(Q0, [0.02, 0.012, 0.03, 0.2], check_bounds=False)
    with pytest.raises(InvalidDescription, match="finite lower"):
        parse(two_link('shape="solid_circle" diameter="{d}"',
                       'shape="solid_circle" diameter="0.03"',
                       params='<pinflex:parameter name="d" value="0.03" design="true"/>'))
    # a design parameter cannot move the geometry; a plain one can
    geo = '<pinflex:point_mass name="p" link="link2" xyz="{L} 0 0" mass="0.1"/>'
    sec = 'shape="solid_circle" diameter="0.03"'
    with pytest.raises(InvalidDescription, match="design parameter"):
        parse(two_link(sec, sec, extra=geo, params='<pinflex:parameter name="L" value="0.45" '
                       'lower="0.1" upper="0.5" design="true"/>'))
    plain = parse(two_link(sec, sec, extra=geo, params='<pinflex:parameter name="L" '
                           'value="0.3"/>'))
    assert plain.point_masses[0].xyz[0] == 0.3


def test_cli_set_reaches_parameters(tmp_path, capsys):
    """``--set d1=...`` sets a parameter; an out-of-bounds value exits 2 naming it."""
    import json

    from pinflex.cli import main

    path = tmp_path / "tubes.urdf"
    path.write_text(TUBES)
    assert main(["modes", str(path), "--planar", "--q", *map(str, Q0), "--set", "d1=0.05",
                 "--modes", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    lit = FlexibleModel(parse(_literal(0.05, 0.003, 0.03, 0.2)), planar=True)
    np.testing.assert_allclose(out["frequencies_hz"], lit.frequencies(Q0)[:2], rtol=1e-12)
    assert main(["modes", str(path), "--set", "d1=0.9"]) == 2
    assert "d1" in capsys.readouterr().err


# ------------------------------------------------------------------ exact Taylor coefficients
def _matrices(model, q, y):
    terms = kinematics.pose_terms(model, np.asarray(q, float)[None])
    M0, Md, K = assembly.assemble(model, terms, BatchAlgebra(1))
    from pinflex.erls.assembly import add_design_masses

    M = add_design_masses(M0, Md.astype(complex) if np.iscomplexobj(y) else Md, y)
    return erls_design.add_to(model, terms, y, M, K, 1)


def test_matrix_jets_in_section_variables_match_complex_step_and_differences():
    """First coefficients against complex step (to 1e-10), second against differences."""
    model = FlexibleModel(parse(TUBES), planar=True)
    y0 = model.y0
    space, Mj, Kj, _, _ = matrix_jets(model, Q0, y0, order=3)
    nj = 2
    for k in range(4):
        h = 1e-20 * y0[k] if y0[k] else 1e-20
        yc = y0.astype(complex)
        yc[k] += 1j * h
        Mc, Kc = _matrices(model, Q0, yc)
        e = tuple(int(i == nj + k) for i in range(space.nvars))
        for jet, cs in ((Mj, Mc), (Kj, Kc)):
            dcs = cs[0].imag / h
            coef = jet[space.index[e]]
            scale = max(np.abs(dcs).max(), 1e-30)
            assert np.abs(coef - dcs).max() <= 1e-10 * scale
        # second order: central differences of the exact matrices
        hs = 1e-3 * y0[k] if y0[k] else 1e-3
        yp, ym = y0.copy(), y0.copy()
        yp[k] += hs
        ym[k] -= hs
        Mp, Kp = model.matrices(Q0, yp)
        Mm, Km = model.matrices(Q0, ym)
        M0, K0 = model.matrices(Q0, y0)
        e2 = tuple(2 * int(i == nj + k) for i in range(space.nvars))
        for jet, p, m, c in ((Mj, Mp, Mm, M0), (Kj, Kp, Km, K0)):
            fd = (p - 2 * c + m) / hs**2 / 2.0
            coef = jet[space.index[e2]]
            scale = np.abs(coef).max()
            if scale == 0.0:
                assert np.abs(fd).max() < 1e-6 * np.abs(c).max() / hs**2
                continue
            assert np.abs(coef - fd).max() <= 1e-5 * scale


def test_eigenvalue_jets_in_diameter_match_exact_model():
    """λ(d1) from the Taylor model: derivatives by differences, values near y0 to h⁵."""
    model = FlexibleModel(parse(TUBES), planar=True)
    tm = pinflex.expand(model, Q0, order=4, modes=(1, 2), joints=[], design=["d1", "t1"])
    lam0 = (2 * np.pi * model.frequencies(Q0)[:2]) ** 2
    np.testing.assert_allclose(tm.eigval_jets[0], lam0, rtol=1e-12)
    h = 1e-4
    for k, name in enumerate(("d1", "t1")):
        yp, ym = model.y0.copy(), model.y0.copy()
        j = model.design_names.index(name)
        yp[j] += h * model.y0[j]
        ym[j] -= h * model.y0[j]
        lp = (2 * np.pi * model.frequencies(Q0, yp)[:2]) ** 2
        lm = (2 * np.pi * model.frequencies(Q0, ym)[:2]) ** 2
        fd = (lp - lm) / (2 * h * model.y0[j])
        np.testing.assert_allclose(tm.eigval_jets[1 + k], fd, rtol=1e-6)
    errs = []
    for step in (0.004, 0.002):
        y = model.y0.copy()
        y[0] += step
        exact = (2 * np.pi * model.frequencies(Q0, y)[:2]) ** 2
        approx = tm.evaluate(Q0[None], y[None], warn=False)[0]
        errs.append(np.max(np.abs(approx / exact - 1)))
    assert errs[0] < 1e-3 and 20 < errs[0] / errs[1] < 45, errs  # p = 4: error ~ h⁵
