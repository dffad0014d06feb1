"""Analytic reference controllers. Each answers SB3's ``predict(obs, deterministic=True) -> (action, state)``,
so the evaluation treats an analytic law and a trained network alike. Observations may be batched."""

from __future__ import annotations

import numpy as np

from agents import tube
from agents.bead_on_bar import BeadTilt
from agents.falling_cat import KaneScher
from agents.gaits import GaitPlanner, snake_planner
from agents.kapitza import DAMPING_MODULATION, KapitzaSwingUp, KapitzaVibration
from agents.lawton import BeanieDeadBeat, CoinPlanner
from agents.rolling_ball import Holonomy, OptimalArc, for_env
from agents.rolling_coin_surface import SteerToTarget
from agents.sleigh import ShakePlanner, TailFirst


class PiccoliKulkarni:
    """Pump a swing (Piccoli & Kulkarni 2005): stand, r = r_min, while the swing moves away
    from the bottom (sin θ · θ̇ > 0); squat, r = r_max, while it moves toward it.

    Each half swing then multiplies 1 − cos(amplitude) by (r_max/r_min)³. The
    law is read off the Swing-v0 observation (cos θ, sin θ, θ̇ scaled, r scaled)
    and needs none of the env's parameters.
    """

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float32)
        away = obs[..., 1] * obs[..., 2] > 0.0
        return np.where(away, -1.0, 1.0).astype(np.float32)[..., None], state


class SkierPumping:
    """Pump a skier along a trail: stand, h = h_max, while climbing (f′ ẋ > 0, moving away from the bottom,
    where the curvature is largest); crouch, h = h_min, while descending.

    Derivation. Between jumps of h the energy E is conserved. A jump h → h′ at
    fixed (x, p), with w = (1 − κh) σ, changes it by

        ΔE = p²/(2m) (1/w′² − 1/w²) + m g cos φ (h′ − h).

    The law jumps up as the skier passes the bottom, where p is largest and
    κ > 0, so w′ < w and the kinetic energy grows by the factor
    ((1 − κ h_min)/(1 − κ h_max))² on top of the lift m g (h_max − h_min); it
    jumps down at the turning point, where p = 0 and only m g cos φ (h_max − h_min)
    is given back, less than the lift since the slope there is steeper. Each
    half-cycle (bottom → turning point) therefore gains
    KE_bottom [((1 − κ h_min)/(1 − κ h_max))² − 1] + m g (h_max − h_min)(1 − cos φ_turn) > 0.
    On a circular trail of radius R the barycentre is a swing of radius R − h and
    this is Piccoli–Kulkarni's law: 1 − cos φ grows by ((R − h_min)/(R − h_max))³
    per half-cycle.

    It reads sin φ (obs[1]) and the speed along the trail (obs[3]) of the
    Skier-v0 observation: climbing ⇔ sin φ · speed > 0.
    """

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float32)
        climbing = obs[..., 1] * obs[..., 3] > 0.0
        return np.where(climbing, 1.0, -1.0).astype(np.float32)[..., None], state


CONTROLLERS = {
    "connenv/Swing-v0": {"pumping": lambda env: PiccoliKulkarni()},
    "connenv/Skier-v0": {"pumping": lambda env: SkierPumping()},
    "connenv/RollingBall-v0": {"arc": for_env(OptimalArc), "holonomy": for_env(Holonomy)},
    "connenv/RollingBallPose-v0": {"holonomy": for_env(Holonomy, pose=True)},
    "connenv/RollingBallGoal-v0": {"arc": for_env(OptimalArc), "holonomy": for_env(Holonomy)},
    "connenv/KozlovShell-v0": {"gaits": lambda env: GaitPlanner(env)},
    "connenv/SnakeSwimmer-v0": {"gaits": snake_planner},
    "connenv/KapitzaPendulum-v0": {
        "kapitza": KapitzaVibration,
        "damped": lambda env: KapitzaVibration(env, modulation=DAMPING_MODULATION),
    },
    "connenv/KapitzaSwingUp-v0": {"swingup": KapitzaSwingUp},
    "connenv/RollingCoin-v0": {"turn_roll_turn": CoinPlanner},
    "connenv/ElroysBeanie-v0": {"dead_beat": BeanieDeadBeat},
    "connenv/RollingCoinSurface-v0": {"steer": SteerToTarget},
    "connenv/BeadOnBar-v0": {"tilt": BeadTilt},
    "connenv/BeadOnBar-v1": {"tilt": BeadTilt},
    "connenv/TubeTwist-v0": {"cap": tube.for_env, "square": lambda env: tube.for_env(env, sides=4)},
    "connenv/ChaplyginSleigh-v0": {"planner": ShakePlanner, "tail_first": TailFirst},
    "connenv/FallingCat-v0": {"kane_scher": KaneScher},
}
"""Reference controllers by env id and name: a factory of the unwrapped env (for the parameters a law needs)."""


def controller_names(env_id: str) -> list[str]:
    """The names `controller` takes for an env: "analytic" (its first controller) and each controller's own."""
    return ["analytic", *CONTROLLERS.get(env_id, {})]


def controller(env_id: str, name: str = "analytic", env=None):
    """The named reference controller of a registered env; "analytic" is its first. env: the env it will drive
    (default: a new one made with the registration's parameters)."""
    import gymnasium as gym

    known = CONTROLLERS.get(env_id)
    if not known:
        raise ValueError(f"no analytic controller for env {env_id!r}; known: {sorted(CONTROLLERS)}")
    if name not in controller_names(env_id):
        raise ValueError(f"no controller {name!r} for {env_id}; valid: {controller_names(env_id)}")
    factory = next(iter(known.values())) if name == "analytic" else known[name]
    return factory((env or gym.make(env_id)).unwrapped)
