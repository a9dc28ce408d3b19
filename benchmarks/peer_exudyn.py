"""Benchmark A's prescribed motion in Exudyn (ANCF cable elements), for bench_simulate.py.

The peer model: each link is a chain of Exudyn ``ANCFCable2D`` elements (planar Euler-Bernoulli
cable, cubic Hermite interpolation of the position, geometrically exact strains) with the
link's mass per length, EA and EI and the same element counts as pinflex's model (4 and 3).
The drive is the same physical joint motion: the root node of link 1 is clamped at the base
with its slope turned by q1(t) (coordinate constraints with time-dependent offsets), the root
node of link 2 shares the position of link 1's tip node and its slope is link 1's tip slope
turned by the elbow angle q2(t) − q1(t) (a coordinate-vector constraint, in Python). After the
stop the joints hold. No damping, no gravity, design masses as given (baseline: none). The
tip deflection is the tip node's position minus the rigid arm's tip at the same joint angles.
Exudyn's generalized-α (index 3, ρ∞ as given) at a fixed step, full Newton with relative and
absolute tolerances 1e-6 (the default tolerances stall at the first step), dense solver.
"""

from __future__ import annotations

import time

import numpy as np


def _cable_arm(angles0, lengths, elements, mass_per_length, EA, EI, tip_masses):
    """A new system: the two links as ANCF cables at absolute angles, point masses at the tips.

    ``angles0``: the links' absolute angles (the first two are used). Returns ``(system container, system, ground coordinate marker, [nodes of link 1, nodes of
    link 2])`` (keep the container alive while the system is used).
    """
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerNodeCoordinate,
        MassPoint2D,
        NodePoint2D,
        NodePoint2DSlope1,
        NodePointGround,
        ObjectANCFCable2D,
        ObjectConnectorCoordinate,
        ObjectGround,
    )

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    mbs.AddObject(ObjectGround())
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    start = np.zeros(2)
    link_nodes = []
    for L, ne, th in zip(lengths, elements, angles0[:2]):
        d = np.array([np.cos(th), np.sin(th)])
        nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[*(start + L * i / ne * d),
                                                                     *d]))
                 for i in range(ne + 1)]
        for a, b in zip(nodes[:-1], nodes[1:]):
            mbs.AddObject(ObjectANCFCable2D(length=L / ne, massPerLength=mass_per_length,
                                            bendingStiffness=EI, axialStiffness=EA,
                                            nodeNumbers=[a, b]))
        link_nodes.append(nodes)
        start = start + L * d
    for nodes, m in zip(link_nodes, tip_masses):
        if m > 0.0:
            p = mbs.AddNode(NodePoint2D(referenceCoordinates=list(
                mbs.GetNodeParameter(nodes[-1], "referenceCoordinates")[:2])))
            mbs.AddObject(MassPoint2D(physicsMass=m, nodeNumber=p))
            for c in (0, 1):
                mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
                    mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[-1], coordinate=c)),
                    mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=p, coordinate=c))]))
    return SC, mbs, m_ground, link_nodes


def exudyn_tip_deflection(motion, *, lengths=(0.6, 0.45), elements=(4, 3), mass_per_length=1.9,
                          EA=69e9 * 7.07e-4, EI=69e9 * 3.97e-8, tip_masses=(0.0, 0.0),
                          after_s=0.1, step_s=1e-4, rho_inf=0.9, sample_hz=5000.0):
    """Simulate the motion in Exudyn; ``(times, deflection (n, 2), cpu_s, steps)``.

    ``motion`` is pinflex's :class:`~pinflex.dynamics.motion.JointMotion` in the absolute link
    angles of benchmark A (q1, q2), whose physical elbow angle is q2 − q1.
    """
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerNodeCoordinate,
        MarkerNodeCoordinates,
        ObjectConnectorCoordinate,
        ObjectConnectorCoordinateVector,
    )

    q0 = motion.q_start
    t_end = motion.t1 + after_s
    SC, mbs, m_ground, link_nodes = _cable_arm(q0, lengths, elements, mass_per_length, EA, EI,
                                               tip_masses)
    angles0 = (q0[0], q0[1])

    def theta1(t):
        return float(motion(t)[0][0])

    def elbow(t):
        q = motion(t)[0]
        return float(q[1] - q[0])

    # link 1 root: position fixed, slope (cos q1, sin q1) (coordinates are displacements)
    root = link_nodes[0][0]
    c10, s10 = np.cos(angles0[0]), np.sin(angles0[0])
    offsets = (lambda mbs, t, i, off: 0.0, lambda mbs, t, i, off: 0.0,
               lambda mbs, t, i, off: np.cos(theta1(t)) - c10,
               lambda mbs, t, i, off: np.sin(theta1(t)) - s10)
    for c, fn in enumerate(offsets):
        mbs.AddObject(ObjectConnectorCoordinate(
            markerNumbers=[m_ground, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=root,
                                                                        coordinate=c))],
            offsetUserFunction=fn))
    # elbow: link 2 root at link 1 tip, slope turned by the elbow angle
    tip1, root2 = link_nodes[0][-1], link_nodes[1][0]
    for c in (0, 1):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=tip1, coordinate=c)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=root2, coordinate=c))]))

    def rot(t):
        a = elbow(t)
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

    def constraint(mbs, t, item, q, q_t, velocity_level):
        # q: the markers' current coordinates (reference included): [x, y, s_x, s_y] twice
        return rot(t) @ q[2:4] - q[6:8]

    def jacobian(mbs, t, item, q, q_t, velocity_level):
        J = np.zeros((2, 8))
        J[:, 2:4] = rot(t)
        J[:, 6:8] = -np.eye(2)
        return J

    mbs.AddObject(ObjectConnectorCoordinateVector(
        markerNumbers=[mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=tip1)),
                       mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=root2))],
        scalingMarker0=np.zeros((2, 1)), constraintUserFunction=constraint,
        jacobianUserFunction=jacobian))
    t, pos, cpu, steps = _solve(exu, mbs, link_nodes, motion.t0, t_end, step_s, rho_inf,
                                sample_hz)
    q = np.array([motion(float(s))[0] for s in t])
    rigid = np.stack([lengths[0] * np.cos(q[:, 0]) + lengths[1] * np.cos(q[:, 1]),
                      lengths[0] * np.sin(q[:, 0]) + lengths[1] * np.sin(q[:, 1])], axis=1)
    return t, pos - rigid, cpu, steps


def _solve(exu, mbs, link_nodes, t0, t_end, step_s, rho_inf, sample_hz, loads_jacobian=0):
    """Generalized-α at a fixed step; ``(times, tip position (n, 2), cpu_s, steps)``."""
    from exudyn.itemInterface import SensorNode

    tip = link_nodes[1][-1]
    sensor = mbs.AddSensor(SensorNode(nodeNumber=tip, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    steps = int(round((t_end - t0) / step_s))
    settings.timeIntegration.numberOfSteps = steps
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.startTime = t0
    settings.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.computeLoadsJacobian = loads_jacobian
    # full Newton, tolerances on the scale of the motion (the defaults stall at the first step)
    settings.timeIntegration.newton.useModifiedNewton = False
    settings.timeIntegration.newton.relativeTolerance = 1e-6
    settings.timeIntegration.newton.absoluteTolerance = 1e-6
    settings.linearSolverType = exu.LinearSolverType.EigenDense
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 1.0 / sample_hz
    c0 = time.process_time()
    mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    cpu = time.process_time() - c0
    data = mbs.GetSensorStoredData(sensor)
    return data[:, 0], data[:, 1:3], cpu, steps


def exudyn_servo_tip_deflection(motion, feedforward, *, kp, kd, lengths=(0.6, 0.45),
                                elements=(4, 3), mass_per_length=1.9, EA=69e9 * 7.07e-4,
                                EI=69e9 * 3.97e-8, tip_masses=(0.0, 0.0), after_s=0.1,
                                step_s=1e-4, rho_inf=0.9, sample_hz=5000.0):
    """The same arm driven by motor torques: computed torque plus PD on the motor angles.

    ``motion`` holds benchmark A's absolute link angles; the motors turn the physical relative
    angles ``r = (q1, q2 − q1)`` (Pinocchio's convention, that of ``feedforward(t)``, the rigid
    computed torque (2,) [N m]). Link 1's root node is held at the base, link 2's root node at
    link 1's tip node; the slopes are free. Each motor is an Exudyn torsional spring-damper
    (``ObjectConnectorTorsionalSpringDamper``, k = kp, d = kd) between rigid markers on the
    cables (the ground and link 1's root; link 1's tip and link 2's root: the stator takes the
    reaction), whose offset, velocity offset and constant torque are set before each step to
    ``r_ref − r_0``, ``ṙ_ref`` and ``−τ_ff`` at the step's end (a pre-step function). The
    tip deflection is the tip node minus the rigid arm at the *measured* motor angles (the
    slope angles, as pinflex reports it). Returns ``(times, deflection (n, 2), cpu_s, steps)``.
    """
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        ObjectConnectorCoordinate,
        ObjectConnectorTorsionalSpringDamper,
        ObjectGround,
        SensorNode,
    )

    q0 = motion.q_start
    t_end = motion.t1 + after_s
    SC, mbs, m_ground, link_nodes = _cable_arm(q0, lengths, elements, mass_per_length, EA, EI,
                                               tip_masses)
    root1, tip1, root2 = link_nodes[0][0], link_nodes[0][-1], link_nodes[1][0]
    for c in (0, 1):  # base position held; elbow: link 2's root at link 1's tip
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
            m_ground, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=root1, coordinate=c))]))
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=tip1, coordinate=c)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=root2, coordinate=c))]))
    cables = [i for i in range(mbs.systemData.NumberOfObjects())
              if mbs.GetObject(i)["objectType"] == "ANCFCable2D"]
    first1, last1, first2 = cables[0], cables[elements[0] - 1], cables[elements[0]]
    ground = mbs.AddObject(ObjectGround())

    def rigid_marker(body, x):
        return mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[x, 0.0, 0.0]))

    def rz(a):
        return np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0],
                         [0.0, 0.0, 1.0]])

    r0 = np.array([q0[0], q0[1] - q0[0]])
    # marker 0 turned by the initial motor angle: the connector's angle is r − r0 (no wrap)
    motors = [mbs.AddObject(ObjectConnectorTorsionalSpringDamper(
        markerNumbers=[rigid_marker(ground, 0.0), rigid_marker(first1, 0.0)], stiffness=kp,
        damping=kd, rotationMarker0=rz(r0[0]))),
        mbs.AddObject(ObjectConnectorTorsionalSpringDamper(
            markerNumbers=[rigid_marker(last1, lengths[0] / elements[0]),
                           rigid_marker(first2, 0.0)], stiffness=kp, damping=kd,
            rotationMarker0=rz(r0[1])))]

    def pre_step(mbs, t):
        te = t + step_s  # generalized-alpha balances the forces at the step's end
        q, qd, _ = motion(te)
        r = np.array([q[0], q[1] - q[0]]) - r0
        rd = np.array([qd[0], qd[1] - qd[0]])
        tau = feedforward(te)
        for k, j in enumerate(motors):
            mbs.SetObjectParameter(j, "offset", float(r[k]))
            mbs.SetObjectParameter(j, "velocityOffset", float(rd[k]))
            mbs.SetObjectParameter(j, "torque", float(-tau[k]))
        return True

    mbs.SetPreStepUserFunction(pre_step)
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Coordinates))
               for n in (root1, tip1, root2)]
    slopes0 = [np.asarray(mbs.GetNodeParameter(n, "referenceCoordinates"))[2:4]
               for n in (root1, tip1, root2)]
    t, pos, cpu, steps = _solve(exu, mbs, link_nodes, motion.t0, t_end, step_s, rho_inf,
                                sample_hz)
    angles = []
    for sensor, s0, near in zip(sensors, slopes0, (q0[0], q0[0], q0[1])):
        s = mbs.GetSensorStoredData(sensor)[:, 3:5] + s0
        a = np.unwrap(np.arctan2(s[:, 1], s[:, 0]))
        angles.append(a + 2.0 * np.pi * np.round((near - a[0]) / (2.0 * np.pi)))
    a1, a_tip, a2 = angles
    q = np.stack([a1, a1 + (a2 - a_tip)], axis=1)  # absolute link angles of the motors
    rigid = np.stack([lengths[0] * np.cos(q[:, 0]) + lengths[1] * np.cos(q[:, 1]),
                      lengths[0] * np.sin(q[:, 0]) + lengths[1] * np.sin(q[:, 1])], axis=1)
    return t, pos - rigid, cpu, steps


def compare_with_exudyn(traj, ref, *, after_s: float, steps_s=(2e-4,)) -> list[dict]:
    """Exudyn's tip deflection and cost at each step of ``steps_s`` against pinflex's ``ref``.

    ``ref`` is pinflex's converged report of the same motion (its ``y`` gives the masses). Each
    row: CPU per simulated second, the largest tip-deflection difference relative to the
    peak of ``ref``, and the difference to the previous (coarser) peer run.
    """
    from pinflex.dynamics.motion import JointMotion

    motion = JointMotion(traj)
    y = dict(ref.y)
    masses = (y.get("m1", 0.0), y.get("m2", 0.0))
    peak = float(np.abs(ref.deflection_m[:, :2]).max())
    simulated = motion.t1 + after_s - motion.t0
    rows: list[dict] = []
    last = None
    for step in steps_s:
        t, d, cpu, steps = exudyn_tip_deflection(motion, tip_masses=masses, after_s=after_s,
                                                 step_s=step)
        ours = np.array([np.interp(t, ref.times_s, ref.deflection_m[:, i]) for i in range(2)]).T
        rows.append({
            "peer": "exudyn", "step_s": step, "steps": steps,
            "model": f"ANCFCable2D 4+3 elements, generalized-alpha (rho_inf 0.9) h = {step:g} s",
            "cpu_per_simulated_s": cpu / simulated,
            "tip_difference": float(np.abs(d - ours).max() / peak),
            "change_from_coarser": (None if last is None or last[0].shape != t.shape else
                                    float(np.abs(d - last[1]).max() / peak)),
            "peer_tip_peak_m": float(np.linalg.norm(d, axis=1).max()),
        })
        last = (t, d)
    return rows


def compare_servo_with_exudyn(motion, feedforward, times, deflection, *, kp, kd, after_s,
                              steps_s=(1e-4,)) -> list[dict]:
    """Exudyn's PD-servo run at each step of ``steps_s`` against pinflex's converged one.

    ``times``, ``deflection`` (n, 2): pinflex's converged tip deflection (baseline design, no
    point masses). Each row: CPU per simulated second, the largest tip-deflection difference
    relative to pinflex's peak, and the change from the previous (coarser) peer run.
    """
    peak = float(np.abs(deflection).max())
    simulated = motion.t1 + after_s - motion.t0
    rows: list[dict] = []
    last = None
    for step in steps_s:
        t, d, cpu, steps = exudyn_servo_tip_deflection(motion, feedforward, kp=kp, kd=kd,
                                                       after_s=after_s, step_s=step)
        ours = np.array([np.interp(t, times, deflection[:, i]) for i in range(2)]).T
        rows.append({
            "peer": "exudyn", "step_s": step, "steps": steps,
            "model": f"ANCFCable2D 4+3 elements, torsional spring-damper motors, "
                     f"generalized-alpha (rho_inf 0.9) h = {step:g} s",
            "cpu_per_simulated_s": cpu / simulated,
            "tip_difference": float(np.abs(d - ours).max() / peak),
            "change_from_coarser": (None if last is None or last[0].shape != t.shape else
                                    float(np.abs(d - last[1]).max() / peak)),
        })
        last = (t, d)
    return rows
