"""Print the reference's self-consistency figures: ``python -m tests.reference.measure_delta_rigid``
(from the repository root). The numbers quoted in tests/unit/test_delta_rigid_reference_self.py."""

from __future__ import annotations

import numpy as np

from tests.reference import delta_rigid as ref
from tests.unit.test_delta_rigid_reference_self import CASES, _trajectory, random_motion, rel


def main() -> None:
    for name, P in CASES.items():
        q, qd, qdd, qddd = random_motion(P, 200, seed=len(name))
        lag = ref.reference_torques(P, q, qd, qdd)
        diag: list = []
        muj = ref.reference_torques(P, q, qd, qdd, method="mujoco", diagnostics=diag)
        r1 = ref.reference_torque_rate(P, q, qd, qdd, qddd)
        r2 = ref.reference_torque_rate(P, q, qd, qdd, qddd, step=5e-3)
        t = np.linspace(0.0, 0.6, 61)
        tq, tqd, tqdd, tqddd = _trajectory(P, t)
        rate = ref.reference_torque_rate(P, tq, tqd, tqdd, tqddd)
        fd = np.zeros_like(tq)
        for k, w in enumerate(ref._FD, start=1):
            for sgn in (1.0, -1.0):
                fd += sgn * w * ref.reference_torques(P, *_trajectory(P, t + sgn * k * 1e-3)[:3])
        fd /= 1e-3
        print(f"{name:36s} lagrange-vs-mujoco {rel(muj, lag):.1e}  closure gap {np.max(diag, axis=0)[0]:.1e} m"
              f"  rate step/2 {rel(r2, r1):.1e}  rate vs time-FD {rel(rate, fd):.1e}")


if __name__ == "__main__":
    main()
