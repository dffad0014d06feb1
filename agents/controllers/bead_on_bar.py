"""Reference controller of BeadOnBar-v0: tilt the bar against the error and the velocity; with g = 0, spin it only
to push the bead outward.

It reads BeadOnBar-v0's observation (r/L, (r* − r)/L, ṙ/L, sin θ, cos θ, hold) and answers SB3's
``predict(obs, deterministic=True) -> (action, state)``, batched or not.
"""

from __future__ import annotations

import numpy as np

RATE = 3.0  # λ, 1/s: the tilt law's three closed-loop poles at −λ
MAX_TILT = 0.5  # rad: the steepest tilt the law asks for
CREEP = 0.8  # the outward speed of the g = 0 law, as a fraction of the success speed tolerance


class BeadTilt:
    """With g > 0, tilt: the bar held still at angle θ gives r̈ = −g sin θ, so asking for the angle

        sin θ_d = (k_p (r − r*) + k_d ṙ) / g,   clipped to ±sin 0.5,

    and turning toward it at θ̇ = k_θ (θ_d − θ) (clipped to ±omega_max) makes, for small angles and dropping the
    centrifugal term r θ̇², r‴ + k_θ r̈ + k_θ k_d ṙ + k_θ k_p (r − r*) = 0. The gains k_θ = 3λ, k_d = λ,
    k_p = λ²/3 put its three poles at −λ, λ = 3/s: no overshoot, settled in about 2 s. Of the two angles with
    sin θ = sin θ_d (the bar through the pivot is the same line at θ and θ + π, with r reversed) it turns toward
    the nearer.

    With g = 0 the bar's angle does nothing and only spinning acts, r̈ = r θ̇² (outward): the law spins only to push
    the bead outward, toward a target farther out, while its outward speed is below v_c = 0.8 × the success
    speed tolerance, at the rate that would bring it to v_c in one step, θ̇ = √((v_c − ṙ_out) / (|r| dt)); then
    it holds the bar still and the bead coasts at constant speed onto the target, slow enough to count as at
    rest there. This traces the inclusion ṙ ≥ 0 at a small constant speed.
    """

    def __init__(self, env):
        """env: the unwrapped BeadOnBar env (for L, g, omega_max, dt and the speed tolerance)."""
        from connenv.envs.bead_on_bar import SPEED_TOLERANCE

        self.L, self.g, self.omega_max, self.dt = env.half_length, env.g, env.omega_max, env.dt
        self.creep = CREEP * SPEED_TOLERANCE * self.L
        self.k_theta, self.k_d, self.k_p = 3.0 * RATE, RATE, RATE**2 / 3.0

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float64)
        r, error, speed = obs[..., 0] * self.L, -obs[..., 1] * self.L, obs[..., 2] * self.L
        rate = self.tilt(error, speed, obs[..., 3], obs[..., 4]) if self.g > 0.0 else self.spin(r, error, speed)
        action = np.clip(rate / self.omega_max, -1.0, 1.0).astype(np.float32)
        return action[..., None], state

    def tilt(self, error, speed, sin_theta, cos_theta):
        """θ̇ toward the nearer angle θ_d of the tilt law."""
        theta = np.arctan2(sin_theta, cos_theta)
        low = np.sin(MAX_TILT)
        target = np.arcsin(np.clip((self.k_p * error + self.k_d * speed) / self.g, -low, low))
        turns = [np.angle(np.exp(1j * (candidate - theta))) for candidate in (target, np.pi - target)]
        turn = np.where(np.abs(turns[0]) <= np.abs(turns[1]), turns[0], turns[1])
        return self.k_theta * turn

    def spin(self, r, error, speed):
        """θ̇ of the spin law: push outward while the target is farther out and the bead slower than v_c."""
        side = np.sign(r)
        outward = side * speed
        wanted = (side * error < 0.0) & (outward < self.creep)
        push = np.sqrt(np.maximum(self.creep - outward, 0.0) / (np.maximum(np.abs(r), 1e-12) * self.dt))
        return np.where(wanted, np.minimum(push, self.omega_max), 0.0)


def tilt(env):
    return BeadTilt(env)


CLONES = {"connenv/BeadOnBar-v0": {"demonstrations": 20}}
"""agents.imitate's diagnosis of the env (agents.imitate.Budget's fields where not its defaults): the tilt law keeps
no memory, so it labels the states of DAgger's rounds."""
