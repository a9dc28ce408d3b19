"""The modal solve on fine meshes and near-singular arms: right or refused, one path.

References are independent of the solve under test: a Richardson extrapolation (h², h⁴ terms)
of moderate meshes, and the same arm with its stiff link declared rigid.
"""

import dataclasses

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import EigenSolverError

Q = np.array([1.817, 5.312])
Y = np.array([0.125, 0.125])
TEXT = TWO_LINK.read_text()


def _arm(n1=4, n2=3):
    text = TEXT.replace('link="link1" elements="4"', f'link="link1" elements="{n1}"')
    text = text.replace('link="link2" elements="3"', f'link="link2" elements="{n2}"')
    return FlexibleModel(parse(text), planar=True)


def _limit(meshes, values):
    """Richardson limit of f(h) = f0 + a h² + b h⁴ through three meshes."""
    h = 1.0 / np.asarray(meshes, dtype=float)
    A = np.column_stack([np.ones(3), h**2, h**4])
    return np.linalg.solve(A, np.asarray(values))[0]


def _both_paths(model, k=3):
    return model.frequencies(Q, Y, n_modes=k), model.modes(Q, Y, n_modes=k).freq_hz


@pytest.mark.parametrize("link", [1, 2])
def test_refined_link_agrees_with_richardson_limit_on_both_paths(link):
    """256 elements on one link: both paths within 1e-8 of the limit of 32/64/128 elements.

    The nodal-coordinate solve was 1.9e-7 (frequencies) and 1.2e-6 (modes) off here.
    """
    make = (lambda n: _arm(n1=n)) if link == 1 else (lambda n: _arm(n2=n))
    coarse = [make(n).frequencies(Q, Y, n_modes=3) for n in (32, 64, 128)]
    limit = np.array([_limit((32, 64, 128), [c[j] for c in coarse]) for j in range(3)])
    f, g = _both_paths(make(256))
    assert np.max(np.abs(f / limit - 1)) < 1e-8
    assert np.max(np.abs(g / limit - 1)) < 1e-8
    assert np.max(np.abs(g / f - 1)) < 1e-12


@pytest.mark.slow
@pytest.mark.parametrize("link", [1, 2])
def test_1024_elements_on_a_link_agree_with_richardson_limit(link):
    """1024 elements on one link: both paths within 1e-7 of the limit (measured ≤ 3e-10)."""
    make = (lambda n: _arm(n1=n)) if link == 1 else (lambda n: _arm(n2=n))
    coarse = [make(n).frequencies(Q, Y, n_modes=3) for n in (32, 64, 128)]
    limit = np.array([_limit((32, 64, 128), [c[j] for c in coarse]) for j in range(3)])
    f, g = _both_paths(make(1024))
    assert np.max(np.abs(f / limit - 1)) < 1e-7
    assert np.max(np.abs(g / limit - 1)) < 1e-7


def _soft_long(E=3.0, rigid_link2=False, length=1000.0, elements=4):
    """Benchmark A with a long link 1 of modulus E (link 2 flexible or rigid)."""
    text = TEXT.replace('<origin xyz="0.6 0 0"/><axis', f'<origin xyz="{length} 0 0"/><axis')
    text = text.replace('name="m1" link="link1" xyz="0.6 0 0"', 'name="m1" link="link1" '
                        f'xyz="{length} 0 0"')
    text = text.replace('link="link1" elements="4"', f'link="link1" elements="{elements}"')
    if rigid_link2:
        start = text.index('<pinflex:flexible link="link2"')
        stop = text.index("</pinflex:flexible>", start) + len("</pinflex:flexible>")
        text = text[:start] + text[stop:]
        exact = repr(1.9 * 0.45 * 0.45**2 / 12.0)  # the rod's own inertia (the file rounds it)
        text = text.replace('iyy="0.01443" iyz="0" izz="0.01443"',
                            f'iyy="{exact}" iyz="0" izz="{exact}"')
        text = text.replace('<mass value="0.855"/>', f'<mass value="{1.9 * 0.45!r}"/>')
    desc = parse(text)
    spec = desc.flexible["link1"]
    flexible = dict(desc.flexible)
    flexible["link1"] = dataclasses.replace(spec, E=E, G=E / 2.6)
    return FlexibleModel(dataclasses.replace(desc, flexible=flexible), planar=True)


def test_near_singular_arm_is_finite_consistent_and_matches_its_rigid_limit():
    """A 1 km, E = 3 Pa link 1 (λ spans 1e-17 to 1e10 rad²/s²): no NaN, one answer.

    Its lowest modes do not deform the 1e10 times stiffer link 2, so they equal those of the
    same arm with link 2 rigid (a model without the stiffness contrast) to ~1e-9.
    """
    model = _soft_long()
    assert model.description.flexible["link1"].length_m == pytest.approx(1000.0)
    f = model.frequencies(Q)
    assert np.all(np.isfinite(f)) and f.size == model.nx
    for k in (1, 3, 8, None):
        g = model.modes(Q, n_modes=k).freq_hz
        assert np.all(np.isfinite(g))
        np.testing.assert_allclose(g[:8], f[: g.size][:8], rtol=1e-12)
    rigid = _soft_long(rigid_link2=True).frequencies(Q, n_modes=8)
    np.testing.assert_allclose(f[:8], rigid, rtol=1e-8)
    # the full set of shapes solves the nodal-coordinate problem and is mass-normalised
    r = model.modes(Q)
    M, K = model.matrices(Q)
    np.testing.assert_allclose(r.shapes.T @ M @ r.shapes, np.eye(model.nx), atol=1e-6)


def test_unresolvable_spectrum_is_refused_not_returned():
    """A 10 km, 64-element, E = 3 Pa link 1: its highest modes have no digit in either form.

    λ spans 27 orders of magnitude; the lowest modes stay right (relative-coordinate form).
    """
    model = _soft_long(length=1e4, elements=64)
    lowest = model.frequencies(Q, n_modes=3)
    assert np.all(np.isfinite(lowest)) and np.all(lowest > 0)
    with pytest.raises(EigenSolverError, match="not resolved"):
        model.frequencies(Q)
    with pytest.raises(EigenSolverError, match="not resolved"):
        model.modes(Q)
