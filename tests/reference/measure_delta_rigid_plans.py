"""Print the worst differences between the library's Delta dynamics/plans and the rigid reference, as checked by
tests/unit/test_delta_rigid_reference.py: ``python -m tests.reference.measure_delta_rigid_plans`` (repository root;
240 plans, 60 of them time-optimal: about as long as that test file)."""

from __future__ import annotations

import numpy as np

from tests.reference import delta_rigid as ref
from tests.unit import test_delta_rigid_reference as T


def main() -> None:
    for name in ("default", "ends", "lumped"):
        profile = T.profile_named(name)
        robot, P = T.robot_of(name), T.reference_params(profile)
        p, v, a, j = T.random_cartesian(300, seed=5)
        q, qd, qdd, qddd = robot.joint_motion(p, v, a, j)
        A, G, dA, dG = robot.split_dynamics(q, qd, qdd, qddd, p, v, a, j)
        rdA, rdG = ref.reference_split_rate(P, q, qd, qdd, qddd)
        print(f"robot {name:8s} torque {T.rel(A + G, ref.reference_torques(P, q, qd, qdd)):.1e}"
              f"  rate {max(T.rel(dA, rdA), T.rel(dG, rdG)):.1e}")
    for name in ("default", "ends"):
        profile = T.profile_named(name)
        P = T.reference_params(profile)
        peak, rate_lim, rated = T.drives(profile)[3:]
        for rule in T.RULES:
            worst = np.zeros(7)
            use = 0.0
            for k, move in enumerate(T.plans(name)):
                pl = move[rule]
                J = pl.joint
                torque = ref.reference_torques(P, J.q, J.qd, J.qdd)
                mine, theirs = T.figures(name, k, rule), T.report_figures(pl)
                near = np.maximum(theirs["rate"], mine["rate"]) >= T.BAND * rate_lim
                far = theirs["rate"] < T.BAND * rate_lim
                worst = np.maximum(worst, [
                    T.rel(J.torque, torque), T.rel(mine["lib_motor"], mine["ref_motor"]),
                    T.rel(mine["lib_rate"], mine["ref_rate"]), T.rel(theirs["rms"], mine["rms"]),
                    (np.abs(theirs["torque"] - mine["torque"]) / peak).max(),
                    (np.abs(theirs["rate"] - mine["rate"]) / rate_lim)[far].max(initial=0.0),
                    (np.abs(theirs["rate"] - mine["rate"]) / mine["rate"])[near].max(initial=0.0)])
                use = max(use, float(np.concatenate([mine["torque"] / peak, mine["rate"] / rate_lim,
                                                     mine["rms"] / rated]).max()))
            print(f"plans {name:7s} {rule:7s} torque {worst[0]:.1e} motor {worst[1]:.1e} rate {worst[2]:.1e}"
                  f" rms {worst[3]:.1e} | report peaks: torque {worst[4]:.1e} of limit, rate far {worst[5]:.1e}"
                  f" of limit, rate near limit {worst[6]:.1e} rel | worst reference utilisation {use:.7f}")


if __name__ == "__main__":
    main()
