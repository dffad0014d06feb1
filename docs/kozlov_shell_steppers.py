"""Stepper benchmark for KozlovShell-v0: 300 steps of seeded uniform random actions, from rest (reduced model)
and with momentum (0.3, 0.1, 0.05) (full model). err = max |pose − reference pose| over the episode
(reference: dop853 rtol 1e-13 atol 1e-15), drift = max |spatial momentum − initial| / |initial|; time = median
µs per env.step. Pass: err ≤ 1e-8 and drift ≤ 1e-8.

    python docs/kozlov_shell_steppers.py
"""

import time, numpy as np, gymnasium as gym, connenv, os, platform, scipy

STEPS = 300


def episode(options, momentum):
    env = gym.make("connenv/KozlovShell-v0", **options).unwrapped
    env.reset(seed=0, options={"state": {"momentum": momentum}})
    rng = np.random.default_rng(0)
    s0 = np.array(env._info()["spatial_momentum"])
    poses, times, drift = [], [], 0.0
    for _ in range(STEPS):
        a = rng.uniform(-1, 1, 2).astype(np.float32)
        t = time.perf_counter()
        _, _, _, _, info = env.step(a)
        times.append(time.perf_counter() - t)
        poses.append(env.y[:3].copy())
        if momentum != (0, 0, 0):
            drift = max(drift, np.linalg.norm(np.array(info["spatial_momentum"]) - s0) / np.linalg.norm(s0))
    return np.array(poses), np.array(times), drift


ref = {m: episode({"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}, m)[0] for m in [(0, 0, 0), (0.3, 0.1, 0.05)]}
print(
    f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}"
)
print("| integrator | options | µs/step reduced | µs/step full | err reduced | err full | drift full | pass |")
print("|---|---|---|---|---|---|---|---|")
cands = [("rk4", {"substeps": s}) for s in (1, 2, 4, 8, 16, 32)]
cands += [(i, {"rtol": r, "atol": r * 1e-2}) for i in ("dop853", "rk45", "lsoda") for r in (1e-6, 1e-8, 1e-10, 1e-12)]
for integ, opts in cands:
    row = []
    errs, drift, us = [], 0.0, []
    for m in [(0, 0, 0), (0.3, 0.1, 0.05)]:
        poses, times, d = episode({"integrator": integ, **opts}, m)
        errs.append(np.abs(poses - ref[m]).max())
        drift = max(drift, d)
        us.append(np.median(times) * 1e6)
    ok = max(errs) <= 1e-8 and drift <= 1e-8
    o = " ".join(f"{k}={v:g}" for k, v in opts.items())
    print(
        f"| {integ} | {o} | {us[0]:.0f} | {us[1]:.0f} | {errs[0]:.1e} | {errs[1]:.1e} | {drift:.1e} | {'pass' if ok else 'FAIL'} |",
        flush=True,
    )
