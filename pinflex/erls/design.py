"""Design parameters that enter ``M`` and ``K`` nonlinearly: sections, materials, springs.

Design point masses enter ``M`` linearly (``M = M0 + Σ y_j M_j``, see
:func:`pinflex.erls.assembly.assemble`). A design *parameter* of a flexible link's section or
material changes the link's beam properties ``c = EA, GJ, EIy, EIz, ρA, ρIp``, each a nonlinear
function ``f_c(y)`` of the parameters (:mod:`pinflex.description.properties`). The link's
beam matrices are linear in those properties, ``K_link = Σ_c f_c K_c``, ``M_link = Σ_c f_c
M_c`` with constant unit matrices, so

    M(q, y) = M_nom(q) + Σ_c (f_c(y) − f_c(y_nom)) M_c(q),   and the same for K,

where ``M_c(q)`` is the unit matrix taken through the ERLS kinematics of the link (and the
joint conditions). A design parameter in a joint spring's stiffness is one more stiffness
channel with the unit matrix ``gᵀg`` (:mod:`pinflex.erls.joints`); a point mass whose value
references a design parameter is a linear mass term of that parameter.

The same ``f_c`` formulas run on floats, per-pose arrays and jets, so the Taylor model's
coefficients in section dimensions are exact (:func:`pinflex.parametric.matrix_jets`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pinflex import beam
from pinflex.checks import check_y
from pinflex.erls import joints as joint_conditions
from pinflex.erls import kinematics
from pinflex.exceptions import InvalidBeamProperty
from pinflex.sections import CHANNELS, beam_properties, section_limits


@dataclass(frozen=True)
class Channel:
    """One design-dependent term ``f(y) · unit`` of ``M`` or ``K``.

    Attributes:
        kind: 'M' or 'K'.
        owner: The flexible link, or the joint of a spring.
        name: Beam property (``EA`` ... ``rhoIp``) or ``stiffness``.
        unit: Unit matrix over the link's assembly rows (beam channels), else None.
    """

    kind: str
    owner: str
    name: str
    unit: np.ndarray | None


@dataclass(frozen=True)
class DesignLayout:
    """The design-dependent terms of a model (``model.plan.design``), fixed at construction.

    Attributes:
        channels: Every design-dependent :class:`Channel` of ``M`` and ``K``.
        links: Flexible links whose section or material depends on a design parameter.
        mass_index: ``{point mass: design index}`` of point masses whose value is a design
            variable (the mass itself, or the design parameter it references).
    """

    channels: tuple[Channel, ...]
    links: tuple[str, ...]
    mass_index: Mapping[str, int]


def layout(model, plan, conditions) -> DesignLayout:
    """Find the design-dependent channels of a model (after the plan and joint layout).

    Args:
        model: The model being built (its description and design variables).
        plan: Its :class:`~pinflex.erls.terms.ModelPlan`.
        conditions: Its :class:`~pinflex.erls.joints.JointLayout`.
    """
    from types import MappingProxyType

    design = {d.name for d in model.design if d.kind == "parameter"}
    index = {d.name: i for i, d in enumerate(model.design)}
    mass_index = {
        p.name: index[p.name if p.design else str(p.mass_ref)]
        for p in model.description.point_masses
        if p.design or p.mass_ref is not None
    }
    channels: list[Channel] = []
    links = []
    for link, bp in plan.beams.items():
        inputs = bp.spec.inputs
        if inputs is None or not set(inputs.parameters()) & design:
            continue
        links.append(link)
        spec = bp.spec
        n, le = spec.elements, spec.length_m / spec.elements
        rows = np.ix_(bp.rows, bp.rows)
        units = {
            "EA": beam.element_stiffness(le, 1.0, 0.0, 0.0, 0.0),
            "GJ": beam.element_stiffness(le, 0.0, 1.0, 0.0, 0.0),
            "EIy": beam.element_stiffness(le, 0.0, 0.0, 1.0, 0.0),
            "EIz": beam.element_stiffness(le, 0.0, 0.0, 0.0, 1.0),
            "rhoA": beam.element_mass(le, 1.0, 0.0),
            "rhoIp": beam.element_mass(le, 0.0, 1.0),
        }
        for name, kind in CHANNELS:
            unit = beam.assemble_line(np.broadcast_to(units[name], (n, 12, 12)))[rows]
            if np.any(unit):  # planar models drop the out-of-plane channels
                unit.setflags(write=False)
                channels.append(Channel(kind, link, name, unit))
    for j, k in conditions.spring_joints:
        ref = conditions.spring_refs.get(j.name)
        if ref is not None and ref in design:
            channels.append(Channel("K", j.name, "stiffness", None))
    return DesignLayout(tuple(channels), tuple(links), MappingProxyType(mass_index))


def channel_values(model, get) -> list:
    """``f_c`` of every channel, with design parameters read through ``get(name)``."""
    props = {}
    out = []
    for ch in model.plan.design.channels:
        if ch.name == "stiffness":
            out.append(get(model.plan.conditions.spring_refs[ch.owner]))
            continue
        if ch.owner not in props:
            props[ch.owner] = beam_properties(model.plan.beams[ch.owner].spec.inputs, get)
        out.append(props[ch.owner][ch.name])
    return out


def check_sections(model, get) -> None:
    """Raise :class:`InvalidBeamProperty` where a design makes a section or property invalid."""
    for link in model.plan.design.links:
        inputs = model.plan.beams[link].spec.inputs
        p = beam_properties(inputs, get)
        limits = section_limits(inputs, get)
        p.update(limits)
        for key in ("A", "Iy", "Iz", "J", "rhoA", "rhoIp", "EA", "GJ", *limits):
            v = np.real(np.asarray(p[key] if not hasattr(p[key], "value") else p[key].value))
            if np.any(~np.isfinite(v)) or np.any(v <= 0.0):
                raise InvalidBeamProperty(
                    f"flexible link '{link}': this design gives {key} = "
                    f"{float(np.ravel(v)[np.argmin(np.ravel(v))]):.4g} <= 0 (e.g. a tube whose "
                    "inner diameter reaches the outer one): keep the design inside the valid "
                    "section range"
                )


def _mm(alg, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``alg.mm`` that multiplies a constant jet by a plain matrix product (exact, cheaper)."""
    from pinflex.erls.terms import BatchAlgebra

    if isinstance(alg, BatchAlgebra) or a.shape[0] == 1:
        return alg.mm(a, b)
    if not np.any(a[1:]):
        return a[0] @ b
    if not np.any(b[1:]):
        return a @ b[0]
    return alg.mm(a, b)


def components(model, terms, alg, which=None) -> list[np.ndarray | None]:
    """Unit matrices ``M_c(q)`` / ``K_c(q)`` over the modal coordinates, one per channel.

    ``which`` (booleans per channel) skips channels whose coefficient is zero (None there).
    """
    if not model.plan.design.channels:
        return []
    twist = kinematics.root_twists(model, terms, alg)
    out: list[np.ndarray | None] = []
    full: list[np.ndarray | None] = []
    cache: dict = {}
    for n, ch in enumerate(model.plan.design.channels):
        if which is not None and not which[n]:
            full.append(None)
            continue
        if ch.name == "stiffness":
            j = next(jj for jj, _ in model.plan.conditions.spring_joints if jj.name == ch.owner)
            gx = joint_conditions.parent_rows(model, terms, alg, twist, [j])
            g = np.concatenate([-gx, alg.const(model.coord_map[j.user_col][None, :])], axis=-1)
            full.append(_mm(alg, np.swapaxes(g, -1, -2), g))
            continue
        if ch.owner not in cache:
            sel, root, jac, _, _ = model.plan.beams[ch.owner].kept
            e = twist[ch.owner]
            bx = alg.const(sel) if e is None else alg.const(sel) + root @ e
            w = np.concatenate([bx, jac @ terms.jac[ch.owner]], axis=-1)
            cache[ch.owner] = (bx, w)
        bx, w = cache[ch.owner]
        nx = model.nx
        if ch.kind == "M":
            full.append(_mm(alg, np.swapaxes(w, -1, -2), ch.unit @ w))
        else:
            k = _mm(alg, np.swapaxes(bx, -1, -2), ch.unit @ bx)
            big = np.zeros(k.shape[:-2] + (nx + model.nv, nx + model.nv))
            big[..., :nx, :nx] = k
            full.append(big)
    T = joint_conditions.transform(model, terms, alg, twist)
    for m in full:
        if T is not None and m is not None:
            m = _mm(alg, np.swapaxes(T, -1, -2), _mm(alg, m, T))
        out.append(m)
    return out


def add_to(model, terms, y: np.ndarray, M: np.ndarray, K: np.ndarray, n_poses: int):
    """``M``, ``K`` at designs ``y`` (ny,) or (n, ny) from the nominal ones (batched poses)."""
    if not model.plan.design.channels:
        return M, K
    from pinflex.erls.terms import BatchAlgebra

    idx = {d.name: i for i, d in enumerate(model.design)}
    nominal = model.y0

    def at(vec):
        return lambda name: vec[..., idx[name]]

    check_sections(model, at(y))
    f = channel_values(model, at(y))
    f0 = channel_values(model, at(nominal))
    which = [bool(np.any(np.asarray(fc) != fc0)) for fc, fc0 in zip(f, f0)]
    if not any(which):  # the nominal design: nothing to add
        return M, K
    comps = components(model, terms, BatchAlgebra(n_poses), which)
    dtype = complex if np.iscomplexobj(y) else float  # complex steps pass through
    M, K = np.array(M, dtype=dtype), np.array(K, dtype=dtype)
    for ch, fc, fc0, C in zip(model.plan.design.channels, f, f0, comps):
        if C is None:
            continue
        delta = np.asarray(fc - fc0)
        scaled = delta[..., None, None] * C
        if ch.kind == "M":
            M += scaled
        else:
            K += scaled
    return M, K


def design_mass(model, y, *, order: int = 0):
    """Mass [kg] that depends on the design: design point masses plus design links' beams.

    A point mass whose value is a design variable counts with that value; a flexible link whose
    section or material is designed counts with its beam mass ``ρA(y) · L``. With ``order=1``
    the gradient (ny,) is returned too, exact (jet arithmetic through the section formulas).

    Args:
        model: The flexible model.
        y: Design values (ny,).
        order: 0 for the mass, 1 for ``(mass, gradient)``.
    """
    from pinflex.jets import JetSpace
    from pinflex.jets.scalar import Scalar, coefficients

    y = check_y(model, y, bounds=False)
    names = list(model.design_names)
    ny = len(names)
    if order and ny:
        space = JetSpace(ny, 1)

        def get(name):
            return Scalar.variable(space, names.index(name), y[names.index(name)])

        total = np.zeros(space.ncoef)
    else:
        space = None

        def get(name):
            return float(y[names.index(name)])

        total = np.zeros(1)
    for link in model.plan.design.links:
        spec = model.plan.beams[link].spec
        rhoA = beam_properties(spec.inputs, get)["rhoA"]
        total = total + (coefficients(space, rhoA) if space else float(rhoA)) * spec.length_m
    for pm in model.description.point_masses:
        if pm.name in model.plan.design.mass_index:
            name = model.design[model.plan.design.mass_index[pm.name]].name
            v = get(name)
            total = total + (coefficients(space, v) if space else float(v))
    if not order:
        return float(total[0])
    grad = total[1:1 + ny] if space is not None else np.zeros(ny)
    return float(total[0]), np.asarray(grad, dtype=float)


def design_model(model, y: np.ndarray):
    """The model whose properties are those of design ``y`` (``model`` itself at its nominal).

    Every property a design parameter sets (section dimensions, material constants, joint
    spring stiffnesses, point masses referencing a parameter) is read from a model built at
    ``y``, through the same description route as :meth:`FlexibleModel.matrices`, so the
    dynamics and the modal analysis of one design agree. Design point masses are read from
    ``y`` by the carriers.

    Args:
        model: The :class:`~pinflex.FlexibleModel`.
        y: Design values (ny,), checked.

    Returns:
        ``model`` when no design parameter leaves its nominal value, else a model at ``y``.
    """
    params = {d.name: float(v) for d, v in zip(model.design, y)
              if d.kind == "parameter" and float(v) != float(d.nominal)}
    if not params:
        return model
    return model.with_values(params)
