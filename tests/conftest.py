"""Shared fixtures and small URDF builders for the tests."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TWO_LINK = ROOT / "urdf" / "two_link.urdf"
UR5 = ROOT / "urdf" / "ur5_flexible.xml"


def single_link_urdf(
    joint: str = "revolute",
    elements: int = 40,
    length: float = 1.0,
    E: float = 2.0e11,
    G: float = 8.0e10,
    density: float = 7800.0,
    A: float = 1.0e-4,
    Iy: float = 2.0e-9,
    Iz: float = 1.0e-9,
    J: float = 1.5e-9,
    extra: str = "",
) -> str:
    """URDF text of one flexible bar on a joint about z (beam along x, normal z)."""
    return f"""<robot name="bar" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="bar"/>
  <joint name="j" type="{joint}"><parent link="base"/><child link="bar"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="bar" elements="{elements}" tip="{length} 0 0" normal="0 0 1">
    <pinflex:material E="{E}" G="{G}" density="{density}"/>
    <pinflex:section A="{A}" Iy="{Iy}" Iz="{Iz}" J="{J}"/>
  </pinflex:flexible>{extra}
</robot>"""


@pytest.fixture(scope="session")
def two_link_planar():
    """Benchmark A in planar mode."""
    from pinflex.erls import FlexibleModel

    return FlexibleModel(TWO_LINK, planar=True)
