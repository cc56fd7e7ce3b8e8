"""A seven-joint arm from a URDF file: read it, compile it (the recursive algorithms of
rigid-body dynamics as straight-line Fortran), let it fall under gravity with its joint
damping and a torque on the shoulder, and check the accelerations against M^-1 Q.

    python example/robot_arm.py [path/to/robot.urdf]

Without an argument it uses the arm shipped with conmech (conmech/symbolic/data/arm7.urdf).
"""
import sys
import time

import numpy as np

import conmech
from conmech import symbolic
from conmech.symbolic.urdf import data_path

path = sys.argv[1] if len(sys.argv) > 1 else data_path("arm7.urdf")
robot = symbolic.read_urdf(path)
print(f"{robot.name}: {len(robot.joints)} movable joints ({', '.join(robot.joint_names)}), "
      f"{len(robot.fixed_joints)} fixed")
print("limits (rad):", np.round(robot.lower, 3), np.round(robot.upper, 3))

t0 = time.perf_counter()
arm = robot.system()        # run-time parameters: g, tau1..tau7, c1..c7 (URDF damping)
print(f"built in {time.perf_counter() - t0:.2f} s (a second run takes the cache)")

n = len(robot.joints)
y0 = np.concatenate([[0.3, -0.5, 0.2, -1.8, 0.1, 1.2, 0.4][:n], np.zeros(n)])
r = conmech.solve_ivp(arm.with_params(tau2=8.0), (0, 5), y0, method="DOP853", rtol=1e-10,
                      atol=1e-10)
print(f"5 s with tau2 = 8 N m: {r.message}, nfev {r.nfev}")
print("final joint angles:", np.round(r.y[:n, -1], 4))

model = symbolic.model_of(arm)
q, v = r.y[:n, -1], r.y[n:, -1]
a = model.call("accel", 0.0, q, v, params=arm.with_params(tau2=8.0).params)
M = model.call("mass", 0.0, q)
Q = model.call("forces", 0.0, q, v, params=arm.with_params(tau2=8.0).params)
print(f"articulated-body accelerations vs M^-1 Q: {np.max(np.abs(a - np.linalg.solve(M, Q))):.1e}")
