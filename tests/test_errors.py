"""Bad inputs raise named pinflex errors that say what to fix."""

import numpy as np
import pytest
from conftest import TWO_LINK, single_link_urdf

from pinflex.checks import check_y
from pinflex.cli import main
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    ConfigurationError,
    DesignVariableNotFound,
    DesignVariableOutOfBounds,
    InvalidBeamProperty,
    JointNotFound,
    LinkNotFound,
    PlanarModelError,
)


def test_unknown_flexible_link():
    """A flexible annotation on a missing link names the link and the available ones."""
    xml = single_link_urdf().replace('link="bar" elements', 'link="arm" elements')
    with pytest.raises(LinkNotFound, match="'arm'.*available links: bar, base"):
        parse(xml)


def test_unknown_joint():
    """Asking for a joint that does not exist lists the joints."""
    m = FlexibleModel(TWO_LINK, planar=True)
    with pytest.raises(JointNotFound, match="'elbow'.*q1, q2"):
        m.joint_index("elbow")


def test_missing_property():
    """A beam without Young's modulus says which attribute is missing."""
    xml = single_link_urdf().replace('E="200000000000.0" ', "")
    with pytest.raises(InvalidBeamProperty, match="attribute 'E' is missing"):
        parse(xml)


@pytest.mark.parametrize("field", ["A", "Iz", "E", "density"])
def test_non_positive_property(field):
    """Zero or negative stiffness and mass properties are rejected with their name."""
    kwargs = {"A": 1e-4, "Iz": 1e-9, "E": 2e11, "density": 7800.0}
    kwargs[field] = -1.0
    with pytest.raises(InvalidBeamProperty, match=f"{field}=-1.0 must be a positive"):
        parse(single_link_urdf(**kwargs))


def test_zero_length_beam():
    """A beam whose tip coincides with its root is rejected."""
    with pytest.raises(InvalidBeamProperty, match="zero length"):
        parse(single_link_urdf(length=0.0))


def test_zero_elements():
    """A beam needs at least one element."""
    with pytest.raises(InvalidBeamProperty, match="elements=0 must be >= 1"):
        parse(single_link_urdf(elements=0))


def test_design_value_outside_bounds():
    """Design values outside the URDF's bounds raise with the bounds in the message."""
    m = FlexibleModel(TWO_LINK, planar=True)
    with pytest.raises(DesignVariableOutOfBounds, match=r"'m2' = 0.3 .*\[0, 0.25\]"):
        m.frequencies([1.8, 5.3], [0.1, 0.3])
    with pytest.raises(DesignVariableOutOfBounds):
        FlexibleModel(TWO_LINK, values={"m1": -0.1})
    with pytest.raises(DesignVariableNotFound, match="m1, m2"):
        check_y(m, {"m9": 0.1})


def test_wrong_number_of_joint_values():
    """A pose with the wrong number of joint values names the joints."""
    m = FlexibleModel(TWO_LINK, planar=True)
    with pytest.raises(ConfigurationError, match=r"expected 2 joint values \(q1, q2\)"):
        m.frequencies([1.0, 2.0, 3.0])


def test_planar_mode_rejects_spatial_arm():
    """The planar option refuses an arm whose joint axes are not parallel."""
    from conftest import UR5

    with pytest.raises(PlanarModelError, match="parallel revolute axes"):
        FlexibleModel(UR5, planar=True)


def test_cli_reports_errors_without_traceback(capsys):
    """The CLI turns a pinflex error into one line on stderr and exit code 2."""
    code = main(["modes", str(TWO_LINK), "--q", "1.0", "--planar"])
    assert code == 2
    assert "expected 2 joint values" in capsys.readouterr().err


def test_cli_modes_json(capsys):
    """`pinflex modes --json` prints ndof, rigid_modes and ascending frequencies."""
    import json

    assert main(["modes", str(TWO_LINK), "--q", "1.817", "5.312", "--planar", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ndof"] == 23 and out["rigid_modes"] == 2
    f = np.array(out["frequencies_hz"])
    assert f.size == 21 and np.all(np.diff(f) > 0)
    m = FlexibleModel(TWO_LINK, planar=True)
    np.testing.assert_allclose(f, m.frequencies([1.817, 5.312]), rtol=1e-12)
