"""Reference controller of Skier-v0: pumping, stand while climbing and crouch while descending."""

from __future__ import annotations

import numpy as np


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


def pumping(env):
    return SkierPumping()
