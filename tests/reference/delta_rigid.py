"""Independent rigid-body reference of the Delta robot's inverse dynamics (tests only).

Written from the geometry conventions of ``pickplace_cli/robots/delta.py``'s docstring alone; no code of the
library is used. Two independent derivations of the same model, which the tests hold to each other:

* ``method="lagrange"`` (default, vectorised): T(q, q̇) assembled from every body's velocity, the plate
  from an independent forward kinematics (trilateration), τ = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q with every
  derivative with respect to q taken by the complex step (exact to rounding, no truncation error).
* ``method="mujoco"``: a MuJoCo closed-chain model (three hinge arms; per arm two rods on ball joints at the
  elbow, closed at the plate by ``connect`` constraints; the plate on three slide joints). For a prescribed
  motion, ``mj_inverse`` with the constraint solver disabled gives the generalised forces f of the open tree;
  the actuator torques τ and constraint forces λ solve Sᵀτ + J_cᵀλ = f (least squares: the two rods of a
  parallelogram make one constraint per arm redundant, which leaves λ but not τ undetermined).

The model (SI; base frame at the fixed platform's centre, z up): arm i at φ_i = 0°, 120°, 240°; elbow
E_i = Rz(φ_i)(R + L cos q_i, 0, −L sin q_i); plate joint C_i = p + Rz(φ_i)(r, 0, 0), the plate translates.
Bodies: upper arm (``upper_arm_inertia`` about its motor axis, mass ``upper_arm_mass`` at ``upper_arm_com``
for gravity); a point mass ``elbow_mass`` at the elbow; per forearm pair two slender rods (no inertia about
their own axis) made of end fittings (point masses ``forearm_end_elbow`` at the elbow end,
``forearm_end_plate`` at the plate end, per pair) and the rod body of mass m_rod = ``forearm_pair`` − ends
with its centre of mass at the rod's middle and ``forearm_rod_inertia`` (per pair, about its centre of mass,
perpendicular to the rod; None = uniform rod m_rod·l²/12); the plate ``plate_mass`` + ``payload``.
Joint-side torques τ [N·m], gravity ``g`` included, q > 0 moves an arm down.

Accuracy: ``lagrange`` is exact to rounding (≈1e-14 relative); ``mujoco`` carries the floor values MuJoCo
needs for massless bodies (1e-12 kg / kg·m²; ≈1e-10 relative). :func:`reference_torque_rate` is an 8th-order
central difference of the torque along the motion, relative error ≲ 1e-9 (tests/unit/
test_delta_rigid_reference.py measures both).
"""

from __future__ import annotations

import numpy as np

PHI = np.deg2rad([0.0, 120.0, 240.0])
_C, _S = np.cos(PHI), np.sin(PHI)

#: the default profile's values (profiles/delta-su2018.yaml); the end fittings default to none
DEFAULT_PARAMS: dict = {
    "R": 0.150, "r": 0.051, "L": 0.325, "l": 0.800,
    "upper_arm_mass": 1.0, "upper_arm_inertia": 0.030, "upper_arm_com": 0.13,
    "elbow_mass": 0.10, "forearm_pair": 0.30, "forearm_end_elbow": 0.0, "forearm_end_plate": 0.0,
    "forearm_rod_inertia": None, "plate_mass": 0.40, "payload": 0.1, "g": 9.80665,
}


def params(**changes) -> dict:
    """The default parameters with ``changes`` (KeyError for an unknown name)."""
    out = dict(DEFAULT_PARAMS)
    for k, v in changes.items():
        if k not in out:
            raise KeyError(f"unknown Delta reference parameter {k!r}")
        out[k] = v
    return out


def lumped_params(base: dict) -> dict:
    """The old lumped model as a rigid one: ⅔ of each pair's mass at the elbow, ⅓ at the plate, no rod body."""
    m = base["forearm_pair"]
    return {**base, "forearm_end_elbow": 2.0 * m / 3.0, "forearm_end_plate": m / 3.0, "forearm_rod_inertia": 0.0}


def params_from_robot(robot) -> dict:
    """The parameters of a ``DeltaRobot`` (its fields only; the end fittings default to none)."""
    rod_inertia = getattr(robot, "forearm_rod_inertia", None)
    return {
        "R": robot.R, "r": robot.r, "L": robot.L, "l": robot.l,
        "upper_arm_mass": robot.upper_arm_mass, "upper_arm_inertia": robot.upper_arm_inertia,
        "upper_arm_com": robot.upper_arm_com, "elbow_mass": robot.elbow_mass, "forearm_pair": robot.forearm_mass,
        "forearm_end_elbow": getattr(robot, "forearm_end_elbow", 0.0),
        "forearm_end_plate": getattr(robot, "forearm_end_plate", 0.0),
        "forearm_rod_inertia": rod_inertia, "plate_mass": robot.plate_mass, "payload": robot.payload, "g": robot.g,
    }


def _resolved(P: dict) -> dict:
    """``P`` with m_rod, I_rod (per pair) and the plate's total mass filled in."""
    m_rod = P["forearm_pair"] - P["forearm_end_elbow"] - P["forearm_end_plate"]
    if m_rod < -1e-12 * max(P["forearm_pair"], 1.0):
        raise ValueError(f"end fittings {P['forearm_end_elbow']} + {P['forearm_end_plate']} kg exceed the pair's "
                         f"{P['forearm_pair']} kg")
    m_rod = max(m_rod, 0.0)
    inertia = P["forearm_rod_inertia"]
    return {**P, "m_rod": m_rod, "I_rod": m_rod * P["l"] ** 2 / 12.0 if inertia is None else inertia,
            "m_plate_total": P["plate_mass"] + P["payload"]}


# ------------------------------------------------------------------------------------------- kinematics
def _rz(v_local: np.ndarray) -> np.ndarray:
    """Arm-frame vectors (..., 3 arms, 3) to the base frame (rotation by φ_i about z)."""
    x, y, z = v_local[..., 0], v_local[..., 1], v_local[..., 2]
    return np.stack((_C * x - _S * y, _S * x + _C * y, z), axis=-1)


def elbows(P: dict, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """E, E′ = ∂E/∂q, E″, each (N, 3 arms, 3 xyz); q may be complex."""
    R, L = P["R"], P["L"]
    c, s = np.cos(q), np.sin(q)
    zero = np.zeros_like(c)
    E = _rz(np.stack((R + L * c, zero, -L * s), axis=-1))
    E1 = _rz(np.stack((-L * s, zero, -L * c), axis=-1))
    E2 = _rz(np.stack((-L * c, zero, L * s), axis=-1))
    return E, E1, E2


def _plate_offsets(P: dict) -> np.ndarray:
    """Rz(φ_i)(r, 0, 0), (3 arms, 3)."""
    return np.stack((P["r"] * _C, P["r"] * _S, np.zeros(3)), axis=-1)


def forward_kinematics(P: dict, q: np.ndarray) -> np.ndarray:
    """Plate position (N, 3) for joint angles q (N, 3): the intersection of the three spheres of radius l
    about c_i = E_i − Rz(φ_i)(r, 0, 0) below the elbows (trilateration, then two Newton steps)."""
    q = np.atleast_2d(np.asarray(q, float))
    E, _, _ = elbows(P, q)
    c = E - _plate_offsets(P)
    c1, c2, c3 = c[:, 0], c[:, 1], c[:, 2]
    n = np.cross(c2 - c1, c3 - c1)
    M = np.stack((2.0 * (c2 - c1), 2.0 * (c3 - c1), n), axis=1)
    rhs = np.stack(((c2 * c2).sum(1) - (c1 * c1).sum(1), (c3 * c3).sum(1) - (c1 * c1).sum(1), (n * c1).sum(1)), 1)
    p0 = np.linalg.solve(M, rhs[..., None])[..., 0]
    nn = (n * n).sum(1)
    t = np.sqrt(np.maximum(P["l"] ** 2 - ((p0 - c1) ** 2).sum(1), 0.0) / nn)
    t = np.where(n[:, 2] > 0, -t, t)  # the lower of the two intersections
    p = p0 + t[:, None] * n
    for _ in range(2):
        d = p[:, None, :] - c
        f = 0.5 * ((d * d).sum(-1) - P["l"] ** 2)
        p = p - np.linalg.solve(d, f[..., None])[..., 0]
    return p


def inverse_kinematics(P: dict, p: np.ndarray) -> np.ndarray:
    """Joint angles (N, 3) for plate positions p (N, 3), knee-out branch (d_i·E_i′ > 0).

    In arm i's frame the plate joint is C′ = (x_c, y_c, z_c); ‖C′ − E‖ = l with E = (R + L cos q, 0, −L sin q)
    reads (x_c − R) cos q − z_c sin q = K, K = (‖C′ − (R,0,0)‖² + L² − l²)/(2L), i.e. ρ cos(q + β) = K."""
    p = np.atleast_2d(np.asarray(p, float))
    R, L, l = P["R"], P["L"], P["l"]
    xc = _C * p[:, :1] + _S * p[:, 1:2] + P["r"]
    yc = -_S * p[:, :1] + _C * p[:, 1:2]
    zc = np.repeat(p[:, 2:3], 3, axis=1)
    K = ((xc - R) ** 2 + yc**2 + zc**2 + L * L - l * l) / (2.0 * L)
    rho = np.hypot(xc - R, zc)
    if np.any(np.abs(K) > rho):
        raise ValueError("a plate position is out of reach of the reference Delta")
    beta = np.arctan2(zc, xc - R)
    best = None
    for sign in (1.0, -1.0):
        q = -beta + sign * np.arccos(K / rho)
        q = np.mod(q + np.pi, 2 * np.pi) - np.pi
        # knee-out: d·E′ > 0 with d = C′ − E, E′ = (−L sin q, 0, −L cos q)
        dE = -(xc - R - L * np.cos(q)) * L * np.sin(q) - (zc + L * np.sin(q)) * L * np.cos(q)
        best = q if best is None else np.where(dE > 0, q, best)
    return best


def _jacobian(P: dict, q, p):
    """ṗ = J q̇: A ṗ = B q̇ with A's rows d_i = C_i − E_i and B = diag(d_i·E_i′) (from ‖d_i‖² = l²)."""
    E, E1, E2 = elbows(P, q)
    d = p[:, None, :] + _plate_offsets(P) - E
    B = (d * E1).sum(-1)
    J = np.linalg.solve(d, B[:, :, None] * np.eye(3))
    return J, E, E1, E2, d


def cartesian_motion(P: dict, q, qd, qdd):
    """Plate p, ṗ, p̈ (each (N, 3)) for a joint motion, by the differentiated loop closure
    d_i·ḋ_i = 0,  d_i·d̈_i + ‖ḋ_i‖² = 0,  ḋ_i = ṗ − E_i′q̇_i,  d̈_i = p̈ − E_i′q̈_i − E_i″q̇_i²."""
    q, qd, qdd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd, qdd))
    p = forward_kinematics(P, q)
    J, E, E1, E2, d = _jacobian(P, q, p)
    v = np.einsum("nij,nj->ni", J, qd)
    dd = v[:, None, :] - E1 * qd[..., None]
    rhs = (d * E1).sum(-1) * qdd + (d * E2).sum(-1) * qd**2 - (dd * dd).sum(-1)
    a = np.linalg.solve(d, rhs[..., None])[..., 0]
    return p, v, a


# ------------------------------------------------------------------------------------------ Lagrangian
def _gram(X, Y):
    """Xᵀ Y per sample: (N, 3, 3) from (N, 3 xyz, 3 joints) each (no conjugation)."""
    return np.swapaxes(X, -1, -2) @ Y


def _mass_matrix(P: dict, q, p) -> np.ndarray:
    """M(q) (N, 3, 3) with T = ½ q̇ᵀMq̇ summed body by body (complex q, p allowed: no conjugation)."""
    J, E, E1, E2, d = _jacobian(P, q, p)
    eye = np.eye(3)
    M = P["upper_arm_inertia"] * eye + (P["m_plate_total"] + 3.0 * P["forearm_end_plate"]) * _gram(J, J)
    for i in range(3):
        JE = E1[:, i, :, None] * eye[i]  # Ė_i = E_i′ q̇_i: (N, 3 xyz, 3 joints)
        mid = 0.5 * (JE + J)  # the rod's centre of mass
        rel = J - JE  # the rod's plate end relative to its elbow end: ω × d
        M = M + ((P["elbow_mass"] + P["forearm_end_elbow"]) * _gram(JE, JE) + P["m_rod"] * _gram(mid, mid)
                 + P["I_rod"] / P["l"] ** 2 * _gram(rel, rel))
    return M


def _potential(P: dict, q, p):
    """V(q) (N,) [J]: every mass's height times g."""
    E, _, _ = elbows(P, q)
    zE = E[..., 2]
    g = P["g"]
    arms = (-P["upper_arm_mass"] * P["upper_arm_com"] * np.sin(q)
            + (P["elbow_mass"] + P["forearm_end_elbow"] + 0.5 * P["m_rod"]) * zE).sum(-1)
    plate = (P["m_plate_total"] + 3.0 * P["forearm_end_plate"] + 1.5 * P["m_rod"]) * p[:, 2]
    return g * (arms + plate)


_H = 1e-20  # complex step


def _lagrange_torques(P: dict, q, qd, qdd) -> np.ndarray:
    """τ = d/dt(M q̇) − ∂T/∂q + ∂V/∂q = M q̈ + Ṁ q̇ − ½ q̇ᵀ(∂M/∂q_k)q̇ + ∂V/∂q_k, with Ṁ = ∂M/∂q·q̇ and every
    ∂/∂q by the complex step: M and V at q + ih·δ for δ = q̇, e₁, e₂, e₃ (one stacked evaluation; the plate
    there is p + ih·Jδ, exact to first order in h, which is all the complex step needs)."""
    n = len(q)
    p = forward_kinematics(P, q)
    J0 = _jacobian(P, q, p)[0]
    units = np.broadcast_to(np.eye(3)[:, None, :], (3, n, 3))
    delta = np.concatenate([qd[None], units])  # (4, N, 3)
    qc = (q[None] + 1j * _H * delta).reshape(4 * n, 3)
    pc = (p[None] + 1j * _H * np.einsum("nij,knj->kni", J0, delta)).reshape(4 * n, 3)
    M = _mass_matrix(P, qc, pc).reshape(4, n, 3, 3)
    V = _potential(P, qc[n:], pc[n:]).reshape(3, n)
    M0, Mdot, dM = M[0].real, M[0].imag / _H, M[1:].imag / _H
    dT = 0.5 * np.einsum("ni,knij,nj->nk", qd, dM, qd)
    dV = (V.imag / _H).T
    return (M0 @ qdd[..., None])[..., 0] + (Mdot @ qd[..., None])[..., 0] - dT + dV


def reference_energy(P: dict, q, qd) -> tuple[np.ndarray, np.ndarray]:
    """(T, V), each (N,) [J]: kinetic and potential energy of the rigid model (for power-balance checks)."""
    P = _resolved(P)
    q, qd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd))
    p = forward_kinematics(P, q)
    return 0.5 * np.einsum("ni,nij,nj->n", qd, _mass_matrix(P, q, p), qd), _potential(P, q, p)


# ------------------------------------------------------------------------------------------------ MuJoCo
_FLOOR = 1e-12  # MuJoCo rejects massless moving bodies: the value given to a zero mass or inertia
_W = 0.05  # m, the parallelogram's width (the dynamics do not depend on it)
_MODELS: dict = {}


def _mujoco_xml(P: dict) -> str:
    L, l = P["L"], P["l"]
    Ic = P["upper_arm_inertia"] - P["upper_arm_mass"] * P["upper_arm_com"] ** 2
    if Ic < -1e-15:
        raise ValueError("upper_arm_inertia about the motor axis is below upper_arm_mass·upper_arm_com²")
    Ic = max(Ic, _FLOOR)
    mr, ee, ep = P["m_rod"] / 2.0, P["forearm_end_elbow"] / 2.0, P["forearm_end_plate"] / 2.0  # one rod
    mb = mr + ee + ep
    s = (mr * l / 2.0 + ep * l) / mb if mb > 0 else l / 2.0  # centre of mass from the elbow end
    Ip = P["I_rod"] / 2.0 + mr * (l / 2.0 - s) ** 2 + ee * s**2 + ep * (l - s) ** 2
    mb, Ip = max(mb, _FLOOR), max(Ip, _FLOOR)

    def f(x):
        return repr(float(x))

    arms, eqs, plate_sites = [], [], []
    for i, phi in enumerate(PHI):
        rods = []
        for side, sgn in (("a", 1.0), ("b", -1.0)):
            rods.append(
                f'<body name="rod{i}{side}" pos="{f(L)} {f(sgn * _W / 2)} 0">'
                f'<joint name="ball{i}{side}" type="ball"/>'
                f'<inertial pos="0 0 {f(s)}" mass="{f(mb)}" diaginertia="{f(Ip)} {f(Ip)} {f(_FLOOR)}"/>'
                f'<site name="end{i}{side}" pos="0 0 {f(l)}"/></body>')
            off = np.array([P["r"] * np.cos(phi), P["r"] * np.sin(phi), 0.0]) + sgn * _W / 2 * np.array(
                [-np.sin(phi), np.cos(phi), 0.0])
            plate_sites.append(f'<site name="plate{i}{side}" pos="{f(off[0])} {f(off[1])} {f(off[2])}"/>')
            eqs.append(f'<connect site1="end{i}{side}" site2="plate{i}{side}"/>')
        arms.append(
            f'<body name="arm{i}" pos="{f(P["R"] * np.cos(phi))} {f(P["R"] * np.sin(phi))} 0" '
            f'quat="{f(np.cos(phi / 2))} 0 0 {f(np.sin(phi / 2))}">'
            f'<joint name="q{i}" type="hinge" axis="0 1 0"/>'
            f'<inertial pos="{f(P["upper_arm_com"])} 0 0" mass="{f(max(P["upper_arm_mass"], _FLOOR))}" '
            f'diaginertia="{f(Ic)} {f(Ic)} {f(Ic)}"/>'
            f'<body name="elbow{i}" pos="{f(L)} 0 0"><inertial pos="0 0 0" mass="{f(max(P["elbow_mass"], _FLOOR))}" '
            f'diaginertia="{f(_FLOOR)} {f(_FLOOR)} {f(_FLOOR)}"/></body>' + "".join(rods) + "</body>")
    plate = (f'<body name="plate"><joint name="px" type="slide" axis="1 0 0"/>'
             f'<joint name="py" type="slide" axis="0 1 0"/><joint name="pz" type="slide" axis="0 0 1"/>'
             f'<inertial pos="0 0 0" mass="{f(max(P["m_plate_total"], _FLOOR))}" '
             f'diaginertia="{f(_FLOOR)} {f(_FLOOR)} {f(_FLOOR)}"/>' + "".join(plate_sites) + "</body>")
    return (f'<mujoco model="delta"><option gravity="0 0 {f(-P["g"])}"/><worldbody>' + "".join(arms) + plate
            + "</worldbody><equality>" + "".join(eqs) + "</equality></mujoco>")


def mujoco_model(P: dict):
    """(model, data) of the closed-chain MuJoCo Delta for parameters ``P`` (cached; the constraint solver
    is disabled: the constraints enter through their Jacobian in :func:`_mujoco_torques`)."""
    import mujoco

    P = _resolved(P)
    key = tuple(sorted((k, v) for k, v in P.items()))
    if key not in _MODELS:
        m = mujoco.MjModel.from_xml_string(_mujoco_xml(P))
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
        _MODELS[key] = (m, mujoco.MjData(m))
    return _MODELS[key]


def _frame(z: np.ndarray, hint: np.ndarray) -> np.ndarray:
    """A rotation matrix whose third column is the unit vector z."""
    x = np.cross(hint, z)
    x /= np.linalg.norm(x)
    return np.stack((x, np.cross(z, x), z), axis=1)


def _mujoco_torques(P: dict, q, qd, qdd, diagnostics: list | None = None) -> np.ndarray:
    import mujoco

    m, dat = mujoco_model(P)
    P = _resolved(P)
    l = P["l"]
    p, v, a = cartesian_motion(P, q, qd, qdd)
    E, E1, E2 = elbows(P, q)
    names = [(i, s) for i in range(3) for s in "ab"]
    ends = [m.site(f"end{i}{s}").id for i, s in names]
    plates = [m.site(f"plate{i}{s}").id for i, s in names]
    hinge = [m.joint(f"q{i}") for i in range(3)]
    S = np.zeros((3, m.nv))
    for i, jnt in enumerate(hinge):
        S[i, jnt.dofadr[0]] = 1.0
    out = np.empty_like(q)
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    jq = np.zeros((3, m.nv))
    for n in range(len(q)):
        qpos, qvel, qacc = dat.qpos, dat.qvel, dat.qacc
        for i in range(3):
            adr = hinge[i]
            qpos[adr.qposadr[0]], qvel[adr.dofadr[0]], qacc[adr.dofadr[0]] = q[n, i], qd[n, i], qdd[n, i]
            phi = PHI[i]
            t = np.array([-np.sin(phi), np.cos(phi), 0.0])  # the motor axis (tangential)
            c, s_ = np.cos(q[n, i]), np.sin(q[n, i])
            Rz = np.array([[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]])
            R_arm = Rz @ np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]])
            d = p[n] + np.array([P["r"] * np.cos(phi), P["r"] * np.sin(phi), 0.0]) - E[n, i]
            dd = v[n] - E1[n, i] * qd[n, i]
            ddd = a[n] - E1[n, i] * qdd[n, i] - E2[n, i] * qd[n, i] ** 2
            R_rod = _frame(d / l, t)
            w_abs, wd_abs = np.cross(d, dd) / l**2, np.cross(d, ddd) / l**2
            w_arm, wd_arm = qd[n, i] * t, qdd[n, i] * t
            quat = np.empty(4)
            mujoco.mju_mat2Quat(quat, (R_arm.T @ R_rod).ravel())
            for side in "ab":
                jnt = m.joint(f"ball{i}{side}")
                qpos[jnt.qposadr[0]:jnt.qposadr[0] + 4] = quat
                qvel[jnt.dofadr[0]:jnt.dofadr[0] + 3] = R_rod.T @ (w_abs - w_arm)
                qacc[jnt.dofadr[0]:jnt.dofadr[0] + 3] = R_rod.T @ (wd_abs - wd_arm + np.cross(w_abs, w_arm))
        for k, name in enumerate(("px", "py", "pz")):
            jnt = m.joint(name)
            qpos[jnt.qposadr[0]], qvel[jnt.dofadr[0]], qacc[jnt.dofadr[0]] = p[n, k], v[n, k], a[n, k]
        mujoco.mj_inverse(m, dat)
        f = dat.qfrc_inverse.copy()
        rows, gap = [], 0.0
        for e, pl in zip(ends, plates):
            mujoco.mj_jacSite(m, dat, jp, jr, e)
            mujoco.mj_jacSite(m, dat, jq, jr, pl)
            rows.append(jp - jq)
            gap = max(gap, float(np.abs(dat.site_xpos[e] - dat.site_xpos[pl]).max()))
        Jc = np.concatenate(rows)
        K = np.concatenate((S, Jc)).T  # f = Sᵀτ + J_cᵀλ
        sol, *_ = np.linalg.lstsq(K, f, rcond=None)
        out[n] = sol[:3]
        if diagnostics is not None:
            # closure gap [m]; velocity-constraint residual J_c q̇ [m/s]; force-balance residual [N, N·m]
            diagnostics.append((gap, float(np.abs(Jc @ dat.qvel).max()), float(np.abs(K @ sol - f).max())))
    return out


# ------------------------------------------------------------------------------------------------- API
def reference_torques(P: dict, q, qd, qdd, method: str = "lagrange", diagnostics: list | None = None) -> np.ndarray:
    """Joint-side torques (N, 3) [N·m] of the rigid model for joint motion q, q̇, q̈ (each (N, 3)), gravity
    included. ``method``: "lagrange" (vectorised, exact to rounding) or "mujoco" (per sample; ``diagnostics``
    receives (closure gap, J_c q̇, force residual) per sample)."""
    q, qd, qdd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd, qdd))
    if method == "lagrange":
        return _lagrange_torques(_resolved(P), q, qd, qdd)
    if method == "mujoco":
        return _mujoco_torques(P, q, qd, qdd, diagnostics)
    raise ValueError(f"method must be 'lagrange' or 'mujoco', got {method!r}")


#: 8th-order central difference weights for f′ at offsets ±1..±4 steps
_FD = np.array([4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0])


def reference_split(P: dict, q, qd, qdd, method: str = "lagrange") -> tuple[np.ndarray, np.ndarray]:
    """(A, G), each (N, 3) [N·m]: the static part G = τ(q, 0, 0) (gravity) and the rest A = τ − G."""
    total = reference_torques(P, q, qd, qdd, method)
    zero = np.zeros_like(np.atleast_2d(np.asarray(q, float)))
    static = reference_torques(P, q, zero, zero, method)
    return total - static, static


def _directional_rate(f, q, qd, qdd, qddd, step: float) -> np.ndarray:
    """d/dε f(q + εq̇, q̇ + εq̈, q̈ + εq⃛) at ε = 0 by an 8th-order central difference (step: see below; the
    eight shifted motions in one stacked call of f)."""
    n = len(q)
    scale = np.maximum.reduce([np.linalg.norm(qd, axis=1), np.sqrt(np.linalg.norm(qdd, axis=1)),
                               np.cbrt(np.linalg.norm(qddd, axis=1)), np.full(n, 1e-9)])
    eps = (step / scale)[:, None]
    k = np.array([1, 2, 3, 4, -1, -2, -3, -4], float)[:, None, None] * eps  # (8, N, 1)
    values = f(*((x[None] + k * dx[None]).reshape(8 * n, 3) for x, dx in ((q, qd), (qd, qdd), (qdd, qddd))))
    values = values.reshape(8, n, 3)
    rate = sum(w * (values[i] - values[i + 4]) for i, w in enumerate(_FD))
    return rate / eps


def reference_torque_rate(P: dict, q, qd, qdd, qddd, method: str = "lagrange", step: float = 1e-2) -> np.ndarray:
    """dτ/dt (N, 3) [N·m/s] along the motion: the derivative of τ(q + εq̇, q̇ + εq̈, q̈ + εq⃛) at ε = 0
    (= ∂τ/∂q q̇ + ∂τ/∂q̇ q̈ + ∂τ/∂q̈ q⃛ exactly), by an 8th-order central difference in ε. The step is
    ``step`` times the motion's own time scale 1/max(‖q̇‖, ‖q̈‖^½, ‖q⃛‖^⅓) per sample, so the joints move
    ≲ ``step`` rad: truncation ~step⁸, rounding ~1e-16/step — relative error ≲ 1e-10 on the Delta
    (measured ≈ 1e-13: ``python -m tests.reference.measure_delta_rigid``)."""
    q, qd, qdd, qddd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd, qdd, qddd))
    return _directional_rate(lambda a, b, c: reference_torques(P, a, b, c, method), q, qd, qdd, qddd, step)


def reference_split_rate(P: dict, q, qd, qdd, qddd, method: str = "lagrange",
                         step: float = 1e-2) -> tuple[np.ndarray, np.ndarray]:
    """(dA/dt, dG/dt), each (N, 3) [N·m/s]: the time derivatives of :func:`reference_split`'s parts (same
    difference and accuracy as :func:`reference_torque_rate`)."""
    q, qd, qdd, qddd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd, qdd, qddd))
    dG = _directional_rate(lambda a, b, c: reference_torques(P, a, 0.0 * a, 0.0 * a, method), q, qd, qdd, qddd, step)
    return reference_torque_rate(P, q, qd, qdd, qddd, method, step) - dG, dG
