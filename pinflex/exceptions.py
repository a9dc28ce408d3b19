"""Named exceptions and warnings of pinflex.

Every error derives from :class:`PinflexError` and says what was wrong, what was expected
and how to fix it. Warnings derive from :class:`PinflexWarning`.
"""

from __future__ import annotations

from collections.abc import Iterable


class PinflexError(Exception):
    """Root of all pinflex errors."""


class InvalidDescription(PinflexError):
    """The robot description (URDF or its pinflex annotations) is malformed."""


class LinkNotFound(InvalidDescription):
    """A link name does not exist in the robot description."""

    def __init__(self, name: str, available: Iterable[str]):
        self.name = name
        self.available = sorted(available)
        super().__init__(
            f"link '{name}' is not in the robot description; available links: "
            f"{', '.join(self.available)}"
        )


class JointNotFound(InvalidDescription):
    """A joint name does not exist in the robot description."""

    def __init__(self, name: str, available: Iterable[str]):
        self.name = name
        self.available = sorted(available)
        super().__init__(
            f"joint '{name}' is not in the robot description; available joints: "
            f"{', '.join(self.available)}"
        )


class InvalidBeamProperty(InvalidDescription):
    """A beam property is missing, non-finite or non-positive, or a beam has zero length."""


class UnsupportedJoint(InvalidDescription):
    """A joint type that the ERLS layer does not handle (only revolute, prismatic, fixed)."""


class DesignVariableNotFound(PinflexError):
    """A design variable name is unknown."""

    def __init__(self, name: str, available: Iterable[str]):
        self.name = name
        self.available = sorted(available)
        super().__init__(
            f"design variable '{name}' does not exist; declared design variables: "
            f"{', '.join(self.available) or '(none)'}"
        )


class DesignVariableOutOfBounds(PinflexError):
    """A design variable value lies outside its declared bounds."""

    def __init__(self, name: str, value: float, lower: float, upper: float):
        self.name, self.value, self.lower, self.upper = name, value, lower, upper
        super().__init__(
            f"design variable '{name}' = {value:g} is outside its bounds "
            f"[{lower:g}, {upper:g}]; choose a value inside the bounds or widen them in the URDF"
        )


class ConfigurationError(PinflexError):
    """Joint values of the wrong shape or outside what the model accepts."""


class ImmutableModelError(PinflexError, AttributeError):
    """A constant object (a built ``FlexibleModel``) was asked to change: build a new one."""


class PlanarModelError(PinflexError):
    """The planar option was asked for a robot that does not move in one plane."""


class EigenSolverError(PinflexError):
    """The generalized eigenproblem could not be solved reliably."""


class PreloadBuckles(EigenSolverError):
    """A preload (gravity, payload) makes the stiffness indefinite: the arm buckles under it."""


class PreloadNotInEquilibrium(ConfigurationError):
    """A free joint carries a static load of a preload: the arm has no static state there."""

    def __init__(self, joints):
        self.joints = list(joints)
        said = "; ".join(
            f"'{n}': static load {t:.4g} {'N' if kind == 'prismatic' else 'N m'}, stiffness "
            f"{k:.4g} {'N/m' if kind == 'prismatic' else 'N m/rad'}"
            for n, t, k, kind in self.joints)
        super().__init__(
            f"the preload acts on free joints ({said}): a free joint under a static load is "
            "not in equilibrium, so there is no static state to vibrate about. Lock them "
            "(joints='locked' or {joint: 'locked'}, --joints locked) or give them springs "
            "(<pinflex:joint stiffness=...>, {joint: k}); a free joint the loads leave neutral "
            "(a vertical axis under gravity) may stay free")


class RepeatedEigenvalue(PinflexError):
    """A Taylor expansion was asked at a repeated or nearly repeated eigenvalue."""

    def __init__(self, mode: int, cluster: Iterable[int], eigvals: Iterable[float], gap: float):
        self.mode = mode
        self.cluster = list(cluster)
        self.eigvals = list(eigvals)
        self.gap = gap
        super().__init__(
            f"mode {mode} belongs to a cluster of nearly equal eigenvalues (modes {self.cluster}, "
            f"eigenvalues {', '.join(f'{v:.9g}' for v in self.eigvals)}, relative gap {gap:.2e}); "
            "the eigenvalue Taylor recursion is singular there: expand at another point or "
            "break the symmetry"
        )


class TaylorRadiusExceeded(PinflexError):
    """A Taylor model was evaluated beyond its estimated convergence radius."""


class AssignmentInfeasible(PinflexError):
    """The assignment QP has no feasible point (or the solver failed).

    ``refused_by`` names the model that refused: ``"constraints"`` (box and linear rows,
    which are exact), ``"taylor"`` (the partially linear polynomial's floors or bands) or
    ``"exact"`` (floors checked on the exact model as well).
    """

    def __init__(self, message: str, problem=None, result=None, refused_by: str = "taylor"):
        self.problem = problem
        self.result = result
        self.refused_by = refused_by
        super().__init__(message)


class NewtonDivergence(PinflexError):
    """Newton's method for a static equilibrium did not converge."""


class MissingDependency(PinflexError, ImportError):
    """An optional dependency is not installed."""

    def __init__(self, package: str, purpose: str):
        self.package = package
        super().__init__(f"{purpose} needs '{package}': install it with `pip install {package}`")


class PinflexWarning(UserWarning):
    """Root of all pinflex warnings."""


class TaylorRadiusWarning(PinflexWarning):
    """A Taylor model is being evaluated far from its expansion point."""


class AssignmentWarning(PinflexWarning):
    """An assignment answer is feasible but misses its target by more than asked."""


class AssignmentNotImproved(AssignmentWarning):
    """The assigned design's exact (tracked) target error is larger than the one before."""


class PredictionNotConfirmed(AssignmentWarning):
    """The exact model does not confirm the Taylor model's prediction of an answer."""


class FloorsNotMet(AssignmentWarning):
    """A floor, band or mass budget holds on the prediction but not on the exact model."""


class ModeCrossingWarning(PinflexWarning):
    """A mode crosses or veers with another along a trajectory: sorted and tracked differ."""


class TrajectoryWarning(PinflexWarning):
    """A trajectory leaves the joint limits or is otherwise suspicious."""


class SoftSpringWarning(PinflexWarning):
    """A joint spring too soft to matter is treated as a free joint (see erls.joints)."""


class UnsolvedLoadWarning(PinflexWarning):
    """A PRBDM chain's tip statics found no equilibrium under a load (counted as 100 % error).

    A reported deflection loss that includes such a load is a penalty, not a measured error.
    """


class OptimumNotConfirmedWarning(PinflexWarning):
    """A global PRBDM fit's best value was reached by only one of its polished starts.

    Another sample of starts may find a lower optimum; the fit reports how many starts
    reached its best (``starts_at_best``).
    """


class InvalidBeam(InvalidBeamProperty):
    """A PRBDM beam planform is malformed (vertices, widths, thickness or material)."""


class InvalidChain(PinflexError):
    """PRBDM chain parameters are malformed (link lengths off the simplex, non-positive springs)."""


class TruthNotConverged(PinflexError):
    """A reference ("truth") beam solution failed its own convergence or consistency check."""


class MappingFailed(PinflexError):
    """No multistart run of a PRBDM mapping produced a usable model."""


class InvalidTrajectory(PinflexError):
    """A trajectory has the wrong shape, non-finite values or times that do not increase."""


class JointLimitsExceeded(InvalidTrajectory):
    """Trajectory samples lie outside the joint limits."""

    def __init__(self, samples, joints, values, lower, upper):
        self.samples = [int(k) for k in samples]
        self.joints = list(joints)
        self.values = [float(v) for v in values]
        rows = list(zip(self.samples, self.joints, self.values, lower, upper))[:5]
        shown = "; ".join(
            f"sample {k}, {j} = {v:.6g} not in [{lo:.6g}, {hi:.6g}]" for k, j, v, lo, hi in rows
        )
        more = f" (and {len(self.samples) - 5} more)" if len(self.samples) > 5 else ""
        super().__init__(
            f"{len(self.samples)} joint values outside the limits: {shown}{more}; "
            "change the trajectory or the joint limits"
        )


class InvalidPath(PinflexError):
    """A workspace path specification (segments, arcs, timing) is malformed."""


class IKNotConverged(PinflexError):
    """Inverse kinematics did not reach a target point."""

    def __init__(self, sample, point, residual_m, q, tol_m):
        self.sample = int(sample)
        self.point = [float(v) for v in point]
        self.residual_m = float(residual_m)
        self.q = None if q is None else [float(v) for v in q]
        super().__init__(
            f"inverse kinematics did not reach point {self.point} [m] at sample {self.sample}: "
            f"residual {self.residual_m:.3g} m > tolerance {tol_m:.3g} m; the point may be out of "
            "reach or the previous sample too far away (sample the path more densely)"
        )


class InvalidAssignmentProblem(PinflexError):
    """Inputs of the assignment QP have inconsistent shapes or non-finite values."""


class BatchError(PinflexError):
    """A batch study cannot run: bad study settings, cluster or scheduler address."""


class InvalidSweep(BatchError):
    """A ``--sweep KEY=V1,V2`` option names an unknown key or carries an unusable value."""


class StoreError(BatchError):
    """A batch result store cannot be opened or written, or has another schema version."""


class ParameterNotFound(InvalidDescription):
    """A ``{name}`` reference names no ``<pinflex:parameter>``."""

    def __init__(self, name: str, available: Iterable[str], where: str = ""):
        names = ", ".join(sorted(available)) or "(none declared)"
        at = f"{where}: " if where else ""
        super().__init__(
            f"{at}'{{{name}}}' references no parameter; declared parameters: {names} "
            f"(add <pinflex:parameter name=\"{name}\" value=\"...\"/>)"
        )


# --------------------------------------------------------------------- input validation
class SchemaError(InvalidDescription):
    """The pinflex annotations or the URDF around them break the schema.

    One error reports every problem found in the file (``problems``, in file order); its
    class is that of the first problem. Each problem names the file, the line, the element
    and the attribute, and suggests the closest valid name where there is one.
    """

    def __init__(self, message: str, problems=()):
        self.problems = list(problems)
        super().__init__(message)


class UnknownElement(SchemaError):
    """An element (or namespace) that the pinflex schema does not know."""


class UnknownAttribute(SchemaError):
    """An attribute that the element does not have in the pinflex schema."""


class InvalidAttribute(SchemaError, InvalidBeamProperty):
    """An attribute is missing, not a number, not finite, out of range or inconsistent."""


class ImplausibleValue(InvalidAttribute):
    """A value is possible in principle but not for a physical robot link (e.g. E = 70 Pa)."""


class UnreadableFile(InvalidDescription):
    """An input file is missing, binary, not UTF-8 text or too large to be a description."""


class UnsafePath(InvalidDescription):
    """A file named by a description (an overlay's base, a mesh) lies outside the model's
    folder and the package roots; reading it needs an explicit ``allow_paths=True``."""


class NoFlexibleLink(InvalidDescription):
    """A modal analysis was asked of a robot with no flexible link (no elastic modes)."""


class StudyError(ConfigurationError):
    """A TOML study breaks its schema; ``problems`` lists every problem in the file."""

    def __init__(self, message: str, problems=()):
        self.problems = list(problems)
        super().__init__(message)


class ResourceLimitExceeded(PinflexError):
    """A computation would need more memory (or time) than pinflex allows; checked up front."""


class OutputError(PinflexError):
    """An output file or folder cannot be written (exists as the wrong kind, no permission)."""


class ViewerServerError(PinflexError):
    """The local meshcat server could not be started or reached."""


class PlausibilityWarning(PinflexWarning):
    """A value is allowed but unusual for a robot link (check its units)."""


class CostWarning(PinflexWarning):
    """A computation is allowed but estimated to be long or memory-hungry."""


class LinkTooShort(ConfigurationError):
    """A flexible link cannot be cut into the asked number of rigid segments (lumped models)."""


class TooManyModes(ConfigurationError):
    """More modes were asked of a lumped model than its hinges can carry."""


class DampingNotRepresentable(ConfigurationError):
    """The damping asked for has no joint-damping equivalent in an MJCF or URDF export."""


class TooFewSegments(ConfigurationError):
    """No lumped arm with the segments allowed meets the asked tolerance (``--tol``)."""


class LumpedFitWarning(PinflexWarning):
    """A fitted lumped arm misses the ERLS modes or static compliances by more than allowed.

    Too few segments for the modes and poses fitted (or modes that the hinges cannot shape,
    e.g. an axial mode without axial springs): the exported model is that far off.
    """


class LumpedDampingWarning(PinflexWarning):
    """Modal damping mapped to joint damping reaches ratios far from the ones asked.

    A diagonal joint damping cannot give every mode the same ratio; the message names the
    modes and the ratios reached (also in the export's report).
    """


class OutputExists(OutputError):
    """An output file exists and overwriting it was not allowed (``--force``)."""


class ModelValidityWarning(PinflexWarning):
    """A motion is fast enough that the terms eq. (1) leaves out matter (see validity)."""


class ModelValidityError(PinflexError):
    """``strict``: a motion is too fast for eq. (1) (:func:`pinflex.erls.validity`)."""

    def __init__(self, message: str, validity=None):
        self.validity = validity
        super().__init__(message)
