"""The schema of the pinflex URDF namespace ``urn:pinflex:urdf:1``, and its checks.

Every pinflex element and attribute is one entry of :data:`SCHEMA`; anything else in the
namespace (a misspelt element such as ``<pinflex:flexibel>``, an unknown attribute such as
``inner_diam``), a prefix ``pinflex`` bound to another URI, or an element in a near-miss
namespace is refused with the file, line, element and attribute, and the closest valid name.

Values are checked in three tiers:

* **impossible** (always refused, :class:`InvalidAttribute`): not a number, NaN or inf, a
  non-positive stiffness, size or density, a negative mass, an inner diameter not below the
  outer one, lower bound above upper bound, a nominal value outside its own bounds,
  ``design="maybe"``, two ``<section>``, ``shape=`` together with ``A``/``Iy``/``Iz``/``J``,
  more than :data:`MAX_ELEMENTS_PER_LINK` elements, values so large that derived quantities
  would overflow (hard upper bounds ``le=``, :data:`MAX_COORDINATE`);
* **non-physical for a robot link** (refused by default, :class:`ImplausibleValue`; a
  :class:`PlausibilityWarning` with ``plausibility="warn"``): E below 1e6 Pa (softer than
  the softest elastomers: ``E="70"`` is 70 Pa, not 70 GPa), a density
  outside [1, 25000] kg/m^3 (given or implied by ``linear_density / A``), a section wider than
  its link is long (``outer_diameter="120"`` is 120 m), a cross-section whose second moments
  are too small for its area (no shape has ``Iy + Iz < A^2 / (2 pi)``);
* **implausible** (always a :class:`PlausibilityWarning`): E below 1e8 Pa (softer than
  engineering plastics) or above 1.5e12 Pa (stiffer than diamond, e.g. a deliberately stiff
  arm standing for a rigid one), a density below 100 or above 23000 kg/m^3, a section wider than a
  third of its link (Euler-Bernoulli beams overestimate the frequencies of stubby beams), a
  torsion constant above the polar moment, a link longer than 100 m, a point mass above 10 t.

**Extending the schema** (one entry each): a new element is one ``"name": Element(...)`` item
of :data:`SCHEMA` (its allowed parents, its attributes, how many per parent, optional
cross-attribute rules); a new attribute is one ``"name": Attr(...)`` item in an element's
``attrs``. ``Attr(reference=True)`` lets a numeric attribute take ``{name}`` instead of a
number (every numeric attribute has ``reference=True`` by default); the names are declared
by an element whose entry has ``declares="name"`` (``<pinflex:parameter>``), and resolving
them (undeclared names, bounds, where design parameters may go) is done by
:mod:`pinflex.description.params` after these checks.
Parsing the values into dataclasses stays in :mod:`pinflex.description.parse`, which runs
after these checks and can trust the attributes it reads.

The checks that walk a document against this table live in
:mod:`pinflex.description.checks` (the plain URDF around: :mod:`pinflex.description.urdf_checks`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TypeGuard

from pinflex.description.types import NAMESPACE
from pinflex.fields import Field

_NS = "{" + NAMESPACE + "}"

#: Most beam elements on one link. Dense modal analysis costs O(n^2) memory and O(n^3) time in
#: the dof count n (6 per node in space, 3 in plane): 4096 elements on one spatial link are
#: about 24,600 dof, 4.8 GB per matrix; the memory estimate of
#: :func:`pinflex.resources.check_model_size` refuses such models before any assembly
MAX_ELEMENTS_PER_LINK = 4096

#: Largest coordinate of a point or vector attribute [m]; the hard bounds of the other
#: attributes (``le=`` in :data:`SCHEMA`) keep every derived quantity (A, I = pi d^4 / 64,
#: element matrices ~ E I / l^3) far from floating-point overflow.
MAX_COORDINATE = 1e6

#: Elements that plain URDF also has at the top level (not flagged as a missing prefix).
URDF_TOP_LEVEL = ("link", "joint", "material", "transmission", "gazebo")

_REFERENCE = re.compile(r"\{[ \t]*([A-Za-z_][A-Za-z0-9_]*)[ \t]*\}", re.ASCII)


#: An attribute of a pinflex element is one field of the schema engine (:mod:`pinflex.fields`).
Attr = Field


Report = Callable[..., None]
Rule = Callable[[dict, Report, "_Context"], None]


@dataclass(frozen=True)
class Element:
    """One pinflex element.

    Attributes:
        parents: Where it may appear: 'robot' (a URDF's root), 'overlay', '<document>' (as
            the root itself) or the name of another pinflex element.
        attrs: Its attributes by name.
        count: ``(min, max)`` occurrences per parent (``max`` None: unbounded).
        rules: Cross-attribute checks ``rule(values, report, context)``.
        declares: Attribute whose value declares a name that ``{name}`` references may use.
        doc: One line of documentation.
    """

    parents: tuple[str, ...]
    attrs: Mapping[str, Attr]
    count: tuple[int, int | None] = (0, None)
    rules: tuple[Rule, ...] = ()
    declares: str | None = None
    doc: str = ""


# --------------------------------------------------------------------- cross-attribute rules
_SHAPES = {
    # shape: (required dimensions, optional dimensions)
    None: (("A", "Iy", "Iz", "J"), ()),
    "solid_circle": (("diameter",), ()),
    "hollow_circle": (("outer_diameter",), ("inner_diameter", "wall")),
    "rectangle": (("width", "height"), ()),
}
_SECTION_VALUES = ("A", "Iy", "Iz", "J", "diameter", "outer_diameter", "inner_diameter",
                   "wall", "width", "height")


def _material_rule(v: dict, report: Report, ctx: _Context) -> None:
    if "G" in ctx.attrib and "poisson" in ctx.attrib:
        report("G", "give G or poisson, not both (G is used and poisson would be ignored)")
    if ("density" in ctx.attrib) == ("linear_density" in ctx.attrib):
        report(None, "give exactly one of density [kg/m^3] or linear_density [kg/m]")
    E, G = v.get("E"), v.get("G")
    if _num(E) and _num(G):
        if G > E:
            report("G", f"G = {G:g} Pa is above E = {E:g} Pa (Poisson's ratio below -0.5); "
                   "check the two moduli", warning=True)
        elif G < E / 50.0:
            report("G", f"G = {G:g} Pa is below E/50 = {E / 50:g} Pa; check the two moduli",
                   warning=True)


def _section_rule(v: dict, report: Report, ctx: _Context) -> None:
    shape = v.get("shape")
    if shape not in _SHAPES:
        return  # the choice check has reported it
    required, optional = _SHAPES[shape]
    present = [k for k in _SECTION_VALUES if k in ctx.attrib]
    for k in present:
        if k not in required and k not in optional:
            if shape is None:
                report(k, f"'{k}' belongs to a named shape; give shape=\"...\" or explicit "
                       "A, Iy, Iz, J")
            elif k in ("A", "Iy", "Iz", "J"):
                report(k, f"shape=\"{shape}\" derives A, Iy, Iz and J; give either the shape "
                       f"or explicit '{k}', not both")
            else:
                report(k, f"'{k}' does not apply to shape=\"{shape}\" (it takes "
                       f"{', '.join(required + optional)})")
    for k in required:
        if k not in ctx.attrib:
            report(k, f"attribute '{k}' is missing" + (f" for shape=\"{shape}\"" if shape else ""))
    if not all(_num(v.get(k)) for k in required):
        return
    if shape == "hollow_circle" and "inner_diameter" in ctx.attrib and "wall" in ctx.attrib:
        report("wall", "give inner_diameter or wall, not both")
        return
    if shape == "hollow_circle" and _num(v.get("wall")) and not (
        0.0 < v["wall"] <= v["outer_diameter"] / 2.0  # half: a solid rod (inner diameter 0)
    ):
        report("wall", f"wall = {v['wall']:g} m must be above 0 and at most half the "
               f"outer_diameter ({v['outer_diameter'] / 2.0:g} m)")
        return
    if shape == "hollow_circle" and _num(v.get("inner_diameter")):
        if v["inner_diameter"] >= v["outer_diameter"]:
            report("inner_diameter", f"inner_diameter = {v['inner_diameter']:g} m must be below "
                   f"outer_diameter = {v['outer_diameter']:g} m")
            return
    if shape is None:
        A, Iy, Iz, J = v["A"], v["Iy"], v["Iz"], v["J"]
        least = A * A / (2.0 * math.pi)  # polar moment of a solid circle: the smallest for A
        if Iy + Iz < 0.5 * least:
            report("Iy", f"Iy + Iz = {Iy + Iz:.4g} m^4 is below half of A^2/(2 pi) = "
                   f"{least:.4g} m^4, less than any cross-section of area {A:g} m^2 can have; "
                   "check the units (A in m^2, I in m^4)", physical=True)
        if J > 1.01 * (Iy + Iz):
            report("J", f"J = {J:g} m^4 is above the polar moment Iy + Iz = {Iy + Iz:g} m^4, "
                   "which no cross-section allows", warning=True)
        extent = 2.0 * math.sqrt(max(Iy, Iz) / A)  # I <= A (h/2)^2 for a section of height h
    else:
        dims = {"solid_circle": ("diameter",), "hollow_circle": ("outer_diameter",),
                "rectangle": ("width", "height")}[shape]
        extent = max(v[k] for k in dims)
        upper = max(ctx.upper.get(k, v[k]) for k in dims)
        if upper > extent:
            ctx.checked.extents_upper[ctx.owner] = upper
    ctx.checked.extents[ctx.owner] = extent


def _point_mass_rule(v: dict, report: Report, ctx: _Context) -> None:
    design = v.get("design", False)
    lower, upper, mass = v.get("lower"), v.get("upper"), v.get("mass", 0.0)
    if not design:
        for k in ("lower", "upper"):
            if k in ctx.attrib:
                report(k, f"'{k}' is ignored because the mass is not a design variable; add "
                       "design=\"true\" or drop the bound", warning=True)
        return
    lo = 0.0 if lower is None else lower
    hi = math.inf if upper is None else upper
    if not (_num(lo) and _num(hi) and _num(mass)):
        return
    if lo > hi:
        report("lower", f"lower bound {lo:g} kg is above upper bound {hi:g} kg")
    elif not lo <= mass <= hi:
        report("mass", f"nominal mass {mass:g} kg is outside its bounds [{lo:g}, {hi:g}] kg")


def _parameter_rule(v: dict, report: Report, ctx: _Context) -> None:
    lower, upper, value = v.get("lower"), v.get("upper"), v.get("value")
    if _num(lower) and _num(upper) and lower > upper:
        report("lower", f"lower bound {lower:g} is above upper bound {upper:g}")
    elif _num(value) and ((_num(lower) and value < lower) or (_num(upper) and value > upper)):
        report("value", f"value {value:g} is outside its bounds "
               f"[{lower if lower is not None else '-inf'}, "
               f"{upper if upper is not None else 'inf'}]")
    if v.get("design"):
        missing = [k for k in ("lower", "upper") if k not in ctx.attrib]
        if missing:
            report(missing[0], "a design parameter needs finite lower and upper bounds")


def _body_rule(v: dict, report: Report, ctx: _Context) -> None:
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    if not all(k not in ctx.attrib or _num(v.get(k)) for k in keys):
        return
    import numpy as np

    g = {k: float(v.get(k, 0.0)) for k in keys}
    inertia = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                        [g["ixz"], g["iyz"], g["izz"]]])
    moments = np.linalg.eigvalsh(0.5 * np.trace(inertia) * np.eye(3) - inertia)
    scale = max(float(np.max(np.abs(inertia))), 1e-300)
    if moments.min() < -1e-9 * scale:
        p = np.sort(np.linalg.eigvalsh(inertia))
        report("ixx", f"the rotational inertia is not a rigid body's: principal moments "
               f"{p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g} kg m^2 must be >= 0 and each at most the "
               "sum of the other two", physical=True)


def _joint_rule(v: dict, report: Report, ctx: _Context) -> None:
    if v.get("locked") and "stiffness" in ctx.attrib:
        report("stiffness", "give either stiffness=\"...\" (a spring) or locked=\"true\", "
               "not both")


_MATERIAL_WHY = "E is in pascals (aluminium is 70e9)"
_DENSITY_WHY = "density is in kg/m^3 (aluminium is 2700)"

#: The pinflex namespace: every element and attribute it knows.
SCHEMA: dict[str, Element] = {
    "overlay": Element(
        parents=("<document>",),
        attrs={
            "base": Attr("text", required=True, doc="upstream URDF: a path or "
                         "example-robot-data:<path>"),
            "name": Attr("text", doc="robot name replacing the upstream one"),
        },
        doc="an upstream URDF used unchanged plus pinflex annotations",
    ),
    "flexible": Element(
        parents=("robot", "overlay"),
        attrs={
            "link": Attr("text", required=True, doc="URDF link made a beam"),
            "elements": Attr("int", required=True, ge=1, le=MAX_ELEMENTS_PER_LINK,
                             doc="number of equal beam elements"),
            "tip": Attr("vec3", unit="m", doc="beam end in the link frame"),
            "normal": Attr("vec3", doc="beam z axis in the link frame"),
            "inertia": Attr("choice", choices=("keep-excess", "keep", "beam-only"),
                            doc="what the beam keeps of the URDF link's inertia: the part "
                            "beyond the beam's own (default), all of it, or none"),
        },
        doc="a link modelled as a straight finite-element beam",
    ),
    "material": Element(
        parents=("flexible",),
        count=(1, 1),
        attrs={
            "E": Attr(required=True, gt=0.0, le=1e20, physical=(1e6, math.inf),
                      plausible=(1e8, 1.5e12), unit="Pa", why=_MATERIAL_WHY, reference=True,
                      doc="Young's modulus"),
            "G": Attr(gt=0.0, le=1e20, physical=(3e5, math.inf), plausible=(0.0, 1e12),
                      unit="Pa", why="G is in pascals",
                      reference=True, doc="shear modulus (default E / (2 (1 + poisson)))"),
            "poisson": Attr(gt=-1.0, lt=0.5, doc="Poisson's ratio (default 0.3)"),
            "density": Attr(gt=0.0, le=1e6, physical=(1.0, 25000.0), plausible=(100.0, 23000.0),
                            unit="kg/m^3", why=_DENSITY_WHY, reference=True,
                            doc="mass density"),
            "linear_density": Attr(gt=0.0, le=1e6, unit="kg/m", reference=True,
                                   doc="mass per unit length"),
        },
        rules=(_material_rule,),
        doc="beam material",
    ),
    "section": Element(
        parents=("flexible",),
        count=(1, 1),
        attrs={
            "shape": Attr("choice", choices=("solid_circle", "hollow_circle", "rectangle"),
                          doc="named shape (or explicit A, Iy, Iz, J)"),
            "A": Attr(gt=0.0, le=1e4, unit="m^2", reference=True, doc="area"),
            "Iy": Attr(gt=0.0, le=1e8, unit="m^4", reference=True, doc="second moment about y"),
            "Iz": Attr(gt=0.0, le=1e8, unit="m^4", reference=True, doc="second moment about z"),
            "J": Attr(gt=0.0, le=1e8, unit="m^4", reference=True, doc="torsion constant"),
            "diameter": Attr(ge=1e-6, le=1e4, unit="m", reference=True, doc="solid_circle"),
            "outer_diameter": Attr(ge=1e-6, le=1e4, unit="m", reference=True, doc="hollow_circle"),
            "inner_diameter": Attr(ge=0.0, le=1e4, unit="m", reference=True,
                                   doc="hollow_circle (default 0)"),
            "wall": Attr(ge=0.0, le=1e4, unit="m", doc="hollow_circle wall thickness "
                         "(instead of inner_diameter)"),
            "width": Attr(ge=1e-6, le=1e4, unit="m", reference=True,
                          doc="rectangle, along beam y"),
            "height": Attr(ge=1e-6, le=1e4, unit="m", reference=True,
                           doc="rectangle, along beam z"),
        },
        rules=(_section_rule,),
        doc="beam cross-section",
    ),
    "point_mass": Element(
        parents=("robot", "overlay"),
        attrs={
            "name": Attr("name", required=True, doc="unique name (design variable name)"),
            "link": Attr("text", required=True, doc="link carrying the mass"),
            "xyz": Attr("vec3", unit="m", doc="position in the link frame"),
            "mass": Attr(ge=0.0, le=1e9, plausible=(0.0, 1e4), unit="kg", reference=True,
                         why="mass is in kg", doc="nominal mass"),
            "design": Attr("bool", doc="whether the mass is a design variable"),
            "lower": Attr(ge=0.0, le=1e9, unit="kg", doc="lower bound of the design variable"),
            "upper": Attr(ge=0.0, le=1e9, unit="kg", doc="upper bound of the design variable"),
        },
        rules=(_point_mass_rule,),
        doc="a point mass on a link, optionally a design variable",
    ),
    "parameter": Element(
        parents=("robot", "overlay"),
        attrs={
            "name": Attr("ident", required=True, reference=False,
                         doc="name used as {name} in numeric attributes"),
            "value": Attr(required=True, reference=False, doc="value [SI]"),
            "lower": Attr(reference=False, doc="lower bound (design parameters need one)"),
            "upper": Attr(reference=False, doc="upper bound (design parameters need one)"),
            "design": Attr("bool", reference=False,
                           doc="a design variable of Taylor models and assignments"),
        },
        rules=(_parameter_rule,),
        declares="name",
        doc="a named number that numeric attributes may reference as {name}",
    ),
    "joint": Element(
        parents=("robot", "overlay"),
        attrs={
            "name": Attr("text", required=True, doc="a moving URDF joint"),
            "stiffness": Attr(gt=0.0, le=1e15, unit="N m/rad or N/m", reference=True,
                              doc="joint spring (revolute: N m/rad, prismatic: N/m)"),
            "damping": Attr(ge=0.0, le=1e15, unit="N m s/rad or N s/m", reference=True,
                            doc="joint damper on the same relative motion (a servo's D gain)"),
            "armature": Attr(ge=0.0, le=1e9, plausible=(0.0, 1e3), unit="kg m^2 or kg",
                             reference=True, why="armature = rotor inertia x gear ratio^2",
                             doc="reflected rotor inertia, rotor inertia x gear ratio^2 (as "
                             "Pinocchio's model.armature and MuJoCo's armature)"),
            "locked": Attr("bool", doc="the joint is held fixed"),
        },
        rules=(_joint_rule,),
        doc="joint condition: a spring or a lock (the default; joints='free' or 'locked' "
        "override it)",
    ),
    "body": Element(
        parents=("robot", "overlay"),
        attrs={
            "name": Attr("name", required=True, doc="unique name"),
            "link": Attr("text", required=True, doc="link carrying the body"),
            "xyz": Attr("vec3", unit="m", doc="centre of mass in the link frame"),
            "mass": Attr(required=True, gt=0.0, le=1e9, plausible=(0.0, 1e4), unit="kg",
                         why="mass is in kg", doc="mass"),
            **{k: Attr(ge=0.0 if k in ("ixx", "iyy", "izz") else None, le=1e9, unit="kg m^2",
                       doc=f"{k} of the rotational inertia about the centre of mass, link axes")
               for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
        },
        rules=(_body_rule,),
        doc="a rigid body with mass and rotational inertia on a link (a motor, a flange, a "
        "tool); on a beam it moves with the section at its centre of mass",
    ),
    "coordinates": Element(
        parents=("robot", "overlay"),
        count=(0, 1),
        attrs={"convention": Attr("choice", required=True, choices=("relative", "absolute"),
                                  doc="user joint coordinates")},
        doc="user-facing joint coordinates",
    ),
}


# --------------------------------------------------------------------- plain URDF numbers
_XYZ = Field("vec3", unit="m", doc="position")
_RPY = Field("vec3", le=1e3, unit="rad", doc="roll, pitch, yaw")
_ORIGIN = {"xyz": _XYZ, "rpy": _RPY}
_LENGTH = Field(gt=0.0, le=MAX_COORDINATE, unit="m")
_GEOMETRY = {
    "box": {"size": Field("vec3", unit="m", doc="box edges")},
    "cylinder": {"radius": _LENGTH, "length": _LENGTH},
    "capsule": {"radius": _LENGTH, "length": _LENGTH},
    "sphere": {"radius": _LENGTH},
    "mesh": {"scale": Field("vec3", le=1e6, doc="mesh scale factors")},
}

#: Every numeric attribute of plain URDF that Pinocchio reads, by element path below
#: ``<link>`` or ``<joint>``: pinflex checks them with its own number grammar before
#: Pinocchio parses the file, so the two never read a value differently.
URDF_NUMBERS: dict[tuple[str, ...], dict[str, Field]] = {
    ("link", "inertial", "origin"): _ORIGIN,
    ("link", "inertial", "mass"): {"value": Field(le=1e9, unit="kg", doc="link mass")},
    ("link", "inertial", "inertia"): {
        k: Field(ge=-1e12, le=1e12, unit="kg m^2", doc="inertia about the centre of mass")
        for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
    **{("link", kind, "origin"): _ORIGIN for kind in ("visual", "collision")},
    **{("link", kind, "geometry", shape): attrs for kind in ("visual", "collision")
       for shape, attrs in _GEOMETRY.items()},
    ("joint", "origin"): _ORIGIN,
    ("joint", "axis"): {"xyz": Field("vec3", doc="joint axis")},
    ("joint", "limit"): {
        "lower": Field(unit="rad or m", doc="lower joint limit"),
        "upper": Field(unit="rad or m", doc="upper joint limit"),
        "effort": Field(ge=0.0, unit="N m or N", doc="largest effort"),
        "velocity": Field(ge=0.0, unit="rad/s or m/s", doc="largest speed"),
    },
    ("joint", "dynamics"): {"damping": Field(ge=0.0, le=1e12, doc="viscous damping"),
                            "friction": Field(ge=0.0, le=1e12, doc="Coulomb friction")},
    ("joint", "calibration"): {"rising": Field(), "falling": Field()},
    ("joint", "safety_controller"): {
        "soft_lower_limit": Field(), "soft_upper_limit": Field(), "k_position": Field(),
        "k_velocity": Field()},
}


# --------------------------------------------------------------------- checking
@dataclass
class Checked:
    """What the checks learnt for the later physical checks.

    Attributes:
        extents: Largest cross-section dimension [m] by flexible link name.
        extents_upper: The same with every design parameter of a named shape's dimensions
            at its upper bound, where that is larger.
        references: ``(element, attribute, name)`` of every ``{name}`` reference.
        declared: Names declared for references.
    """

    extents: dict[str, float] = field(default_factory=dict)
    extents_upper: dict[str, float] = field(default_factory=dict)
    references: list[tuple[str, str, str]] = field(default_factory=list)
    declared: set[str] = field(default_factory=set)


@dataclass
class _Context:
    element: str
    attrib: dict
    owner: str  # the flexible link the element belongs to ('' if none)
    checked: Checked
    #: ``{attribute: value at the design upper bound}`` of attributes that reference a
    #: design parameter (an assignment may move them there).
    upper: dict = field(default_factory=dict)


def _num(x) -> TypeGuard[float]:
    return isinstance(x, float) and math.isfinite(x)


def attribute_unit(el, key: str) -> str:
    """The unit of attribute ``key`` of a pinflex element ``el`` (``""`` if none)."""
    tag = el.tag.rsplit("}", 1)[-1]
    element = SCHEMA.get(tag)
    attr = None if element is None else element.attrs.get(key)
    return "" if attr is None else attr.unit
