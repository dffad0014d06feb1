"""Reference controllers of the Kapitza pendulum: open-loop vibration of the pivot, and parametric swing-up.

Both read KapitzaPendulum-v0's observation (cos θ, sin θ, θ̇/(2√(g/l)), u/a_max, u̇/v_max along the actuated
axes) and answer SB3's ``predict(obs, deterministic=True) -> (action, state)``, batched or not.
"""

from __future__ import annotations

import math

import numpy as np

KAPITZA_MARGIN = 3.0  # a²ω² = 3 × 2 g l: three times Kapitza's threshold
AMPLITUDE_FRACTION = 0.8  # of the pivot's travel a_max (a ≤ 0.1 l as well, so that a ≪ l)
DAMPING_MODULATION = 0.2  # β: the damped vibration's amplitude swings between 0.8 a and 1.2 a (≤ 0.96 a_max)


class KapitzaVibration:
    """Vibrate the pivot along one axis, u = a cos φ with φ advancing by ω dt per step (Kapitza 1951).

    Vertical vibration with a²ω² > 2 g l holds the pendulum inverted (the averaged potential
    −m g l cos θ + ¼ m a²ω² sin²θ has a minimum there); horizontal vibration with a²ω² > 2 g l makes
    cos θ = 2 g l/(a²ω²) the stable position. By default a = min(0.8 a_max, 0.1 l) and a²ω² = 3 × 2 g l.

    The pivot moves along the chord between samples of the cosine: the command is the constant velocity
    (a cos(φ + ω dt) − u)/dt. The phase φ needs no clock: it is read off the pivot's own state, since
    u = a cos φ, and the previous sample, u − u̇ dt = a cos(φ − ω dt), tells the sign of φ. Sampling lowers the
    mean square pivot velocity, which the averaged force depends on, by sinc²(ω dt/2) (0.98 by default).

    Open loop by default. With `modulation` β > 0 (a vertical pivot only) it also damps the slow swing about
    inverted: in the averaged potential that swing is an oscillator of stiffness ∝ a²ω² − 2 g l, and the
    amplitude a(1 ± β) — the larger while the pendulum moves away from inverted, the smaller while it comes
    back — removes energy every half swing, as a swing pumped in reverse. The slow angular velocity is
    p/(m l²) = θ̇ + u̇₂ sin θ/l, θ̇ less the micromotion the vibration imposes.
    """

    def __init__(
        self,
        env,
        amplitude: float | None = None,
        margin: float = KAPITZA_MARGIN,
        axis: int = 0,
        modulation: float = 0.0,
    ):
        """env: the unwrapped Kapitza env; axis: which actuated axis to vibrate (0, or 1 for a planar pivot)."""
        system = env.system
        self.amplitude = amplitude or min(AMPLITUDE_FRACTION * env.a_max, 0.1 * system.length)
        if not 0.0 < self.amplitude <= env.a_max:
            raise ValueError(f"amplitude={amplitude!r} is out of range: must be in (0, a_max={env.a_max}]")
        if modulation and not (env.pivot == "vertical" and 0.0 < modulation < 1.0):
            raise ValueError(f"modulation={modulation!r} needs a vertical pivot (pivot={env.pivot!r}) and 0 < β < 1")
        self.modulation, self.length = modulation, system.length
        self.theta_dot_scale = 2.0 * math.sqrt(system.g / system.length)
        if self.amplitude * (1.0 + modulation) > env.a_max:
            raise ValueError(
                f"amplitude={self.amplitude:.4g} × (1 + modulation={modulation}) exceeds the travel a_max={env.a_max}"
            )
        if not 0 <= axis < len(env.axes):
            raise ValueError(f"axis={axis!r} is out of range: the pivot {env.pivot!r} has {len(env.axes)} axes")
        self.omega = math.sqrt(2.0 * margin * system.g * system.length) / self.amplitude
        self.phase_step = self.omega * env.dt
        self.dt, self.a_max, self.v_max = env.dt, env.a_max, env.v_max
        self.axis, self.axes = axis, len(env.axes)
        peak = 2.0 * self.amplitude * (1.0 + modulation) * math.sin(min(self.phase_step, math.pi) / 2) / env.dt
        if peak > env.v_max or self.phase_step > math.pi / 4:
            raise ValueError(
                f"a vibration of amplitude {self.amplitude:.4g} m at ω = {self.omega:.4g} rad/s needs chords at "
                f"{peak:.4g} m/s (v_max={env.v_max}) and {2 * math.pi / self.phase_step:.3g} steps a period "
                f"(at least 8): lower the margin or dt, or raise v_max"
            )

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float64)
        u = obs[..., 3 + self.axis] * self.a_max
        u_dot = obs[..., 3 + self.axes + self.axis] * self.v_max
        amplitude = self.amplitude
        if self.modulation:
            away = np.arctan2(-obs[..., 1], -obs[..., 0])  # θ − π, wrapped
            slow = obs[..., 2] * self.theta_dot_scale + u_dot * obs[..., 1] / self.length
            amplitude = amplitude * (1.0 + self.modulation * np.sign(away * slow))
        phase = np.arccos(np.clip(u / amplitude, -1.0, 1.0))
        previous = u - u_dot * self.dt
        mirrored = np.abs(amplitude * np.cos(-phase - self.phase_step) - previous) < np.abs(
            amplitude * np.cos(phase - self.phase_step) - previous
        )
        phase = np.where(mirrored, -phase, phase)
        velocity = (amplitude * np.cos(phase + self.phase_step) - u) / self.dt
        action = np.zeros(obs.shape[:-1] + (self.axes,), np.float32)
        action[..., self.axis] = np.clip(velocity / self.v_max, -1.0, 1.0)
        return action, state


class KapitzaSwingUp:
    """Swing the pendulum up by vertical pivot motion (parametric pumping), then hold it by `KapitzaVibration`.

    Pumping. While u̇ is constant the energy e = E/(m g l) = 2 s² − cos θ (s the observed θ̇/(2√(g/l))) is
    conserved; over a smooth pivot motion it changes at the rate de/dt = −(ü₂/g) ċ, with c = −cos θ the bob's
    height under the pivot in units of l. Placing the pivot at u₂ = β ċ makes ü₂ ≈ −(2ω₀)² β ċ at the
    pendulum's doubled frequency, so de/dt ∝ ċ² ≥ 0: the pivot rises while the bob rises and sinks while it
    falls, parametric resonance at twice the natural frequency, locked to the pendulum's phase. The law
    commands u₂ = a_max · clip(2 ċ/s_b, ±1) · clip(gain (1 − e), ±1), with s_b = √((e + 1)/2) the scaled
    speed at the bottom, so the pumping fades as e approaches the top's e = 1 (and reverses above it).

    Hold. Within `capture` rad of inverted it switches to the Kapitza vibration, which traps a pendulum
    arriving with e ≈ 1 in the averaged potential −cos θ + (margin/2) sin²θ, and its amplitude modulation
    (`modulation`) damps the slow swing that is left. It keeps vibrating until the pendulum is `release` rad
    away; this mode is the recurrent state that `predict` takes and returns, as SB3's recurrent policies do.
    """

    def __init__(
        self,
        env,
        capture: float = 0.15,
        release: float = 0.6,
        gain: float = 3.0,
        tracking: float = 0.02,
        speed: float = 5.0,
        modulation: float = DAMPING_MODULATION,
        **vibration,
    ):
        if env.pivot != "vertical":
            raise ValueError(f"the swing-up pumps with a vertical pivot; this env has pivot={env.pivot!r}")
        self.capture, self.release, self.gain = capture, release, gain
        self.tracking, self.speed = tracking, min(speed, env.v_max)
        self.vibration = KapitzaVibration(env, modulation=modulation, **vibration)
        self.dt, self.a_max, self.v_max = env.dt, env.a_max, env.v_max

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        """state: whether each env is in the holding mode (None, or an episode start: from the observation)."""
        obs = np.asarray(obs, dtype=np.float64)
        cos, sin, s, u = obs[..., 0], obs[..., 1], obs[..., 2], obs[..., 3] * self.a_max
        deviation = np.arccos(np.clip(-cos, -1.0, 1.0))
        holding = np.zeros(cos.shape, bool) if state is None else np.asarray(state, bool).reshape(cos.shape)
        if episode_start is not None:
            holding = holding & ~np.asarray(episode_start, bool).reshape(cos.shape)
        holding = (deviation < self.capture) | (holding & (deviation < self.release))
        e = 2.0 * s * s - cos
        rate = sin * s / np.maximum((e + 1.0) / 2.0, 1e-12)  # ċ in units of its largest value on the orbit
        target = self.a_max * np.clip(rate, -1.0, 1.0) * np.clip(self.gain * (1.0 - e), -1.0, 1.0)
        pump = np.clip((target - u) / self.tracking, -self.speed, self.speed) / self.v_max
        hold, _ = self.vibration.predict(obs)
        return np.where(holding[..., None], hold, pump[..., None]).astype(np.float32), holding


def kapitza(env):
    return KapitzaVibration(env)


def damped(env):
    return KapitzaVibration(env, modulation=DAMPING_MODULATION)


def swingup(env):
    return KapitzaSwingUp(env)


CLONES = {"connenv/KapitzaSwingUp-v0": {"demonstrations": 10, "epochs": 30, "eval_episodes": 50}}
"""agents.imitate's diagnosis of the swing-up (agents.imitate.Budget's fields where not its defaults): fewer
demonstrations, epochs and evaluation episodes than the other envs', whose episodes are many times shorter."""
