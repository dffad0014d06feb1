"""Swing-v0: pump a swing to a target amplitude by standing and squatting."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from connenv.core.steppers import StepperError, control_segments, control_segments_batch, make_stepper
from connenv.core.validation import check_action, check_keys, check_number, check_stepper_options
from connenv.envs.base import RenderedEnv
from connenv.envs.vector import BATCH, SCALAR, TaskVectorEnv
from connenv.systems.swing import Swing

LIFT_FLOOR = 1e-4  # floor of h in the reward's logarithm: amplitude ≈ 0.014 rad
TIME_COST = 0.01  # reward paid per step until success
ENERGY_ERROR_BOUND = 0.1  # |the stepper's energy error| / (m g r_max) past which it has diverged: StepperError


class SwingEnv(RenderedEnv):
    r"""
    ## Description

    A child on a swing pumps it by standing and squatting: the controller assigns
    the distance r from the pivot to the barycentre, an *active constraint*
    (Bressan). The swing is a point mass m on a massless rod of length r,
    at angle θ from the downward vertical, with angular momentum p = m r² θ̇:

        θ̇ = p / (m r²),    ṗ = −m g r sin θ.

    The system is strongly fit for jumps: a jump of r leaves (θ, p) unchanged.
    Shortening r near the bottom and lengthening it at the extremes multiplies
    1 − cos(amplitude) by (r_max/r_min)³ per half swing (Piccoli & Kulkarni 2005).
    The goal is to reach `target_amplitude` as fast as possible.

    ## Action Space

    `Box(-1, 1, (1,), float32)`; actions outside are clipped, a wrong shape or a
    non-finite value raises ValueError.

    | Num | Action | Min | Max |
    |-----|--------|-----|-----|
    | 0 | commanded radius: r = r_min + (a + 1)/2 · (r_max − r_min) | -1 | 1 |

    By default r jumps to the command at the start of the step. With
    `max_radial_speed` set, r moves toward it at that speed instead.

    ## Observation Space

    `Box(4,) float32`:

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | cos θ | -1 | 1 |
    | 1 | sin θ | -1 | 1 |
    | 2 | θ̇ / (2 √(g/r_min)), 1 at the bottom for a swing that just reaches the top at r_min | -ρ² | ρ² |
    | 3 | (r − r_mid) / r_half, r_mid and r_half the centre and half-width of [r_min, r_max] | -1 | 1 |

    ρ = r_max/r_min. Until success the swing is below the top (h < 2), so
    |θ̇| ≤ 2√(g/r_min) before a jump and ρ² times that after one: the bound
    holds for every state an episode can reach, and reset states must respect
    it. Stepping on after success may saturate it.

    ## Rewards

    With h = (E + m g r)/(m g r) the energy above the bottom in units of m g r
    (h = 1 − cos A for a swing of amplitude A; E is conserved at constant r):

        reward = ln(max(h′, 1e-4) / max(h, 1e-4)) − 0.01

    h before the step, h′ after it. The logarithm pays each half swing of
    pumping alike, since pumping multiplies h by (r_max/r_min)³; the constant
    pays for time. Summed to success it is ln(h*/h₀) − 0.01·steps.

    ## Starting State

    θ₀ uniform on ±[0.05, 0.1] rad (np_random), θ̇₀ = 0, r = r_max, t = 0. A
    swing exactly at rest at the bottom cannot be pumped. `reset(options={"state":
    {...}})` sets any of `theta`, `theta_dot` or `p`, `r` exactly.

    ## Episode End

    Terminated when the amplitude implied by the current energy at the current
    radius reaches `target_amplitude` (`info["is_success"]`). Truncated after
    500 steps (25 s at the default dt) by the registration's time limit; the
    ideal pumping schedule needs 10.3 s.

    ## Arguments

    | kwarg | default | range |
    |---|---|---|
    | r_min | 1.6 | (0, r_max) |
    | r_max | 2.0 | (r_min, ∞) |
    | g | 9.81 | (0, ∞) |
    | mass | 1.0 | (0, ∞) |
    | dt | 0.05 | (0, ∞) |
    | target_amplitude | π/2 | (0, π]; π means going over the top |
    | max_radial_speed | None | None or (0, ∞) m/s |
    | integrator | "exact" | "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau" |
    | substeps (euler, semi_implicit_euler, rk4) / rtol, atol (scipy, and exact where r moves) | | see `connenv.core.steppers` |

    The default integrator, the closed-form pendulum flow, is the fastest and the
    most accurate stepper (`python -m connenv.bench precision`, docs/precision/):
    across r_min from 0.05 m and dt from 0.01 to 0.5 s its energy error stays
    within 1e-9 m g r_max over 100 random steps (tests/test_precision.py).

    A stepper that diverges raises `connenv.core.StepperError` naming the stepper,
    dt and the parameters: a non-finite state, or an energy error past
    0.1 m g r_max. The energy error is the change of E over the segments where r
    is held, where E is conserved (a jump's work is exact and not counted),
    summed since reset.

    Every `info` has `"state"` (`theta`, `theta_dot`, `p`, `r`, `t` in SI),
    `"energy"` (E = p²/(2 m r²) − m g r cos θ, J), `"lift"` (h, above),
    `"amplitude"` (rad) and `"is_success"`.
    """

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        r_min: float = 1.6,
        r_max: float = 2.0,
        g: float = 9.81,
        mass: float = 1.0,
        dt: float = 0.05,
        target_amplitude: float = math.pi / 2,
        max_radial_speed: float | None = None,
        integrator: str = "exact",
        **stepper_options,
    ):
        super().__init__(render_mode, check_number("dt", dt, 0.0, open_low=True))
        self.r_min = check_number("r_min", r_min, 0.0, open_low=True)
        self.r_max = check_number("r_max", r_max, self.r_min, open_low=True)
        self.target_amplitude = check_number("target_amplitude", target_amplitude, 0.0, math.pi, open_low=True)
        self.max_radial_speed = (
            None if max_radial_speed is None else check_number("max_radial_speed", max_radial_speed, 0.0, open_low=True)
        )
        self.system = Swing(
            mass=check_number("mass", mass, 0.0, open_low=True), g=check_number("g", g, 0.0, open_low=True)
        )
        check_stepper_options("Swing-v0", stepper_options, type(self))
        self.stepper = make_stepper(integrator, self.system, **stepper_options)

        self.theta_dot_scale = 2.0 * math.sqrt(self.system.g / self.r_min)
        self.target_lift = 1.0 - math.cos(self.target_amplitude)
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.obs_high = np.array([1.0, 1.0, (self.r_max / self.r_min) ** 2, 1.0])
        high = self.obs_high.astype(np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)

        self.y = np.zeros(2)  # (θ, p)
        self.r = self.r_max
        self.t, self.lift = 0.0, 0.0
        self.energy_error = 0.0  # the stepper's: the change of E on held segments since reset

    # -- Gymnasium API -------------------------------------------------------

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = dict(options or {})
        check_keys("reset options", options, {"state"})
        theta = self.np_random.uniform(0.05, 0.1) * self.np_random.choice([-1.0, 1.0])
        self.y, self.r, self.t, self.energy_error = np.array([theta, 0.0]), self.r_max, 0.0, 0.0
        if "state" in options:
            self._set_state(options["state"])
        return self._obs(), self._info()

    def step(self, action):
        r_cmd = self.command(check_action(action, self.action_space)[0])
        lift_before = self.lift
        try:
            for r, r_dot, tau in control_segments(self.r, r_cmd, self.dt, self.max_radial_speed):
                energy = self._energy(r) if r_dot == 0.0 else None
                self.y = self.stepper(self.system, self.y, np.array([r]), np.array([r_dot]), tau)
                if energy is not None:
                    self.energy_error += self._energy(r) - energy
            self.check_energy_error(self.energy_error)
        except StepperError as error:
            raise self._stepper_error(error) from error
        self.r = r + r_dot * tau
        self.t += self.dt
        info = self._info()
        reward = self.reward(lift_before, info["lift"])
        if self.render_mode == "human":
            self.render()
        return self._obs(), reward, info["is_success"], False, info

    def _make_renderer(self):
        from connenv.envs.rendering import SwingRenderer

        return SwingRenderer(self.r_max, self.render_mode, self.metadata["render_fps"])

    def _draw(self, renderer):
        return renderer.draw(self.y[0], self.r, self.r_min, self.t)

    # -- internals -----------------------------------------------------------

    def _set_state(self, state):
        check_keys("options['state']", state, {"theta", "theta_dot", "p", "r"})
        if "theta_dot" in state and "p" in state:
            raise ValueError("options['state'] gives both theta_dot and p; give one of them")
        r = check_number("state r", state.get("r", self.r_max), self.r_min, self.r_max)
        theta = check_number("state theta", state.get("theta", self.y[0]))
        if "p" in state:
            p = check_number("state p", state["p"])
        else:
            p = self.system.mass * r**2 * check_number("state theta_dot", state.get("theta_dot", 0.0))
        bound = self.obs_high[2] * self.theta_dot_scale
        check_number("state theta_dot", p / (self.system.mass * r**2), -bound, bound)
        self.y, self.r = np.array([theta, p]), r

    def parameters(self):
        return {"r_min": self.r_min, "r_max": self.r_max, "g": self.system.g, "mass": self.system.mass}

    def check_energy_error(self, energy_error):
        """StepperError if |the stepper's energy error| (of any row of a batch) passes its bound."""
        bound = ENERGY_ERROR_BOUND * self.system.mass * self.system.g * self.r_max
        drift = abs(energy_error) if np.ndim(energy_error) == 0 else np.max(np.abs(energy_error))
        if not drift <= bound:
            raise StepperError(f"{self.stepper} diverged: |energy error| = {drift:.3g} J > {bound:.3g} J")

    def _energy(self, r):
        """E = p²/(2 m r²) − m g r cos θ at radius r, on Python floats (the system's, without numpy's overhead)."""
        theta, p = float(self.y[0]), float(self.y[1])
        m = self.system.mass
        return p * p / (2 * m * r * r) - m * self.system.g * r * math.cos(theta)

    def _obs(self):
        return self.observe(self.y[0], self.y[1], self.r)

    def _info(self):
        info = self.describe(self.y, self.r, self.t)
        self.lift = info["lift"]  # h of the current state, the next step's h before
        return info

    # -- task: one state on Python floats, or a batch with ops=BATCH (the vector env) ---------

    def command(self, a):
        """The commanded radius of action a."""
        return self.r_min + 0.5 * (a + 1.0) * (self.r_max - self.r_min)

    def reward(self, lift_before, lift_after, ops=SCALAR):
        return ops.log(ops.maximum(lift_after, LIFT_FLOOR) / ops.maximum(lift_before, LIFT_FLOOR)) - TIME_COST

    def observe(self, theta, p, r, ops=SCALAR):
        r_mid, r_half = 0.5 * (self.r_max + self.r_min), 0.5 * (self.r_max - self.r_min)
        bound = self.obs_high[2]
        speed = ops.clip(p / (self.system.mass * r**2) / self.theta_dot_scale, -bound, bound)
        return ops.pack([ops.cos(theta), ops.sin(theta), speed, (r - r_mid) / r_half])

    def describe(self, y, r, t, ops=SCALAR):
        theta, p = y[..., 0], y[..., 1]
        energy, weight = ops.real(self.system.energy(y, r)), self.system.mass * self.system.g * r
        lift = (energy + weight) / weight  # Swing.lift, from the energy at hand
        return {
            "state": {"theta": theta, "theta_dot": p / (self.system.mass * r**2), "p": p, "r": r, "t": t},
            "energy": energy,
            "lift": lift,
            "amplitude": ops.acos(ops.clip(1.0 - lift, -1.0, 1.0)),
            "is_success": ops.flag(lift >= self.target_lift),
        }


class SwingVectorEnv(TaskVectorEnv):
    """Swing-v0 over a batch (``gym.make_vec("connenv/Swing-v0", num_envs=N)``; see ``connenv.envs.vector``).

    Takes Swing-v0's make kwargs; with ``max_radial_speed`` each row ramps for its own time, so
    the steppers get one segment length per row.
    """

    single_env = SwingEnv

    def __init__(self, num_envs: int = 1, max_episode_steps: int | None = None, **kwargs):
        super().__init__(num_envs, max_episode_steps, **kwargs)
        self.y, self.r, self.t = np.zeros((num_envs, 2)), np.full(num_envs, self.env.r_max), np.zeros(num_envs)
        self.energy_error = np.zeros(num_envs)

    def _held_energy(self, y, r, r_dot):
        """E on the rows whose radius is held (the single env's energy check), 0 on the others."""
        return np.where(r_dot[:, 0] == 0.0, self.env.system.energy(y, r[:, 0]), 0.0)

    def _capture(self, i):
        env = self.env
        self.y[i], self.r[i], self.t[i], self.energy_error[i] = env.y, env.r, env.t, env.energy_error

    def _advance(self, actions):
        env = self.env
        r_cmd = env.command(actions[:, 0])
        lift_before = env.system.lift(self.y, self.r)
        segments, r_end = control_segments_batch(self.r, r_cmd, env.dt, env.max_radial_speed)
        segments = [(r[:, None], r_dot[:, None], tau) for r, r_dot, tau in segments]
        self.y, change = self._run_segments(env.system, self.y, segments, self._held_energy)
        self.energy_error = self.energy_error + change
        env.check_energy_error(self.energy_error)
        self.r, self.t = r_end, self.t + env.dt
        return env.reward(lift_before, env.system.lift(self.y, self.r), BATCH)

    def _observe(self):
        return self.env.observe(self.y[:, 0], self.y[:, 1], self.r, BATCH)

    def _describe(self):
        return self.env.describe(self.y, self.r, self.t, BATCH)
