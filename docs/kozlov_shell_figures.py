"""Figures of KozlovShell-v0 quoted in README: the figure-eight per cycle, momentum conservation, full vs reduced,
rate independence, and the gait planner's worst case over 90 directions at 1 m.

    python docs/kozlov_shell_figures.py
"""

import math

import gymnasium as gym
import numpy as np

from connenv.core import make_stepper
from connenv.systems.kozlov_shell import KozlovShell, ReducedKozlovShell

TIGHT = {"integrator": "dop853", "rtol": 1e-12, "atol": 1e-14}


def net(env, actions, state=None):
    env.reset(options={"state": state or {}})
    for a in actions:
        env.step(np.array(a, np.float32))
    return env.state.pose


env = gym.make("connenv/KozlovShell-v0", **TIGHT).unwrapped
R = [(0, -1), (1, -1), (1, 1), (0, 1), (0, 0)]
L = [(0, -1), (-1, -1), (-1, 1), (0, 1), (0, 0)]
X = [(1, -1), (1, 1), (-1, -1), (-1, 1), (0, 0)]
for name, loop in [
    ("square figure-eight (issue), 10 steps", R + L),
    ("right square loop alone", R),
    ("X figure-eight (planner X@1), 5 steps", X),
]:
    g = net(env, loop)
    print(f"{name}: net (x, y, θ) = ({g[0]:+.6f} m, {g[1]:+.6f} m, {g[2]:+.2e} rad), |Δ| = {math.hypot(*g[:2]):.6f} m")
# momentum conservation, full model
for label, kw in [("dop853 rtol 1e-12", TIGHT), ("default dop853 rtol 1e-8", {})]:
    e = gym.make("connenv/KozlovShell-v0", **kw).unwrapped
    _, info = e.reset(options={"state": {"x": 0.3, "theta": 0.4, "momentum": (0.3, -0.1, 0.05)}})
    s0 = np.array(info["spatial_momentum"])
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(300):
        _, _, _, _, info = e.step(rng.uniform(-1, 1, 2).astype(np.float32))
        worst = max(worst, np.abs(np.array(info["spatial_momentum"]) - s0).max())
    print(
        f"spatial momentum, 300 random steps from μ=(0.3,−0.1,0.05), {label}: max drift / |μ_s| = {worst / np.linalg.norm(s0):.1e}"
    )
# full vs reduced at μ = 0
for rtol in (1e-12, 1e-8):
    st = make_stepper("dop853", rtol=rtol, atol=rtol * 1e-2)
    rng = np.random.default_rng(4)
    yf, yr, u, worst = np.zeros(6), np.zeros(3), np.zeros(2), 0.0
    for _ in range(200):
        uc = rng.uniform(-1, 1, 2) * np.array([0.5, 0.25])
        yf = st(KozlovShell(), yf, u, (uc - u) / 0.1, 0.1)
        yr = st(ReducedKozlovShell(), yr, u, (uc - u) / 0.1, 0.1)
        u = uc
        worst = max(worst, np.abs(yf[:3] - yr).max(), np.abs(yf[3:]).max())
    print(f"full vs reduced at μ=0, 200 random steps, dop853 rtol {rtol:g}: max |Δ(x,y,θ)|, |μ| = {worst:.1e}")
LOOP = [(1, -1), (1, 1), (-1, 1), (-0.3, -1), (0.2, 0.4), (0, 0)]
for label, kw in [("rtol 1e-12", TIGHT), ("default", {})]:
    a = net(gym.make("connenv/KozlovShell-v0", dt=0.37, **kw).unwrapped, LOOP)
    b = net(gym.make("connenv/KozlovShell-v0", dt=0.1, **kw).unwrapped, LOOP)
    print(f"rate independence, loop at dt 0.37 vs 0.1, {label}: max |Δ(x,y,θ)| = {np.abs(a - b).max():.1e}")
from agents.controllers.kozlov_shell import gaits  # noqa: E402

env = gym.make("connenv/KozlovShell-v0", max_episode_steps=2000)
p = gaits(env.unwrapped)
worst = (0, None)
for ang in np.linspace(-math.pi, math.pi, 90, endpoint=False):
    obs, _ = env.reset(options={"target": (math.cos(ang), math.sin(ang))})
    done = False
    n = 0
    while not done:
        obs, r, term, trunc, info = env.step(p.predict(obs)[0])
        n += 1
        done = term or trunc
    assert info["is_success"]
    worst = max(worst, (n, ang))
print("worst over 90 directions at 1.0 m:", worst)
