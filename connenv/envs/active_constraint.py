"""ActiveConstraint-v0: any Lagrangian system steered by active constraints, from its metric or its Lagrangian."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from connenv import examples
from connenv.core.backend import ARRAYS, SCALAR, concat, namespace, traced
from connenv.core.integrators import make_stepper
from connenv.core.mechanics import (
    JUMP_ROWS,
    JUMP_STEPPER,
    JumpClass,
    JumpFlow,
    MetricField,
    check_fields,
    check_metric,
    check_system,
    classify,
    hamiltonian,
)
from connenv.core.segments import bounded_segments, bounded_segments_batch, check_drift, run_segments
from connenv.core.state import Fields, vector, within
from connenv.core.steppers import ExactFlow, ExactSegment, check_observable
from connenv.core.validation import (
    MAGNITUDE_BOUND,
    check_bounds,
    check_dt,
    check_number,
    check_stepper_options,
)
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Spec
from connenv.envs.user_task import BuilderTask
from connenv.rendering import CoordinatePlot

DT_MAX = 1.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
ENERGY_ERROR_BOUND = 1e-2  # |the stepper's energy error| / (1 + |E|) past which it has diverged: StepperError

CONTROLS = ("position", "velocity")


@dataclass
class ActiveConstraintState(State):
    """y = (q, p), u, t, and the energy error: the change of E = H_u(u̇ = 0) where u is held, since reset."""

    y: np.ndarray
    u: np.ndarray
    t: float
    energy_error: float


class ActiveConstraintEnv(BuilderTask, TaskEnv):
    r"""
    ## Description

    Any mechanical system steered by *active constraints* (Bressan): the controller assigns the coordinates u = (u¹…uᵐ)
    directly, and the free ones q = (q¹…qⁿ), with their conjugate momenta p, obey Hamilton's equations of

        H_u(q, p) = ½ (p − G12 u̇)ᵀ G11⁻¹ (p − G12 u̇) − ½ u̇ᵀ G22 u̇ + V(q, u),

    T = ½ q̇ᵀ G11 q̇ + q̇ᵀ G12 u̇ + ½ u̇ᵀ G22 u̇ being the kinetic energy in the metric blocks G11, G12, G22 and V the
    potential (docs/physics/framework.md). `system` is any object with integer attributes `n`, `m` and methods
    `metric(q, u) -> (G11, G12, G22)` and `potential(q, u)` broadcasting over leading axes, and optionally
    `vector_field(y, u, u_dot)` (else H_u is differentiated numerically); or build it from sympy expressions, with exact
    gradients, by `ActiveConstraintEnv.from_lagrangian(kinetic, potential, q, u, **kwargs)`.

    With A = G11⁻¹, K = A G12 and B = G22 − G12ᵀ A G12, the system's class `env.unwrapped.jump_class`
    (`connenv.core.JumpClass`) decides which controls are admissible:

    | class | test | u may | default control |
    |---|---|---|---|
    | strongly fit | K ≡ 0, ∂B/∂q ≡ 0 | jump; (q, p) unchanged | "position" |
    | fit | ∂B/∂q ≡ 0 | jump; (q, p) follow the jump equations (DOP853 at 1e-13) | "position" |
    | general | ∂B/∂q ≢ 0 | move at a bounded speed only | "velocity" |

    ## Action Space

    `Box(-1, 1, (m,), float32)`, by `control`:

    - `control="position"`: u jumps at the step's start, or heads at `max_control_speed` (per coordinate), to the
      command u_low + (a + 1)/2 (u_high − u_low); needs finite bounds and, without that speed, a (strongly) fit system.
    - `control="velocity"`, for a coordinate that winds (infinite bounds): u̇ = a · max_control_speed through the step,
      a coordinate stopping at a finite bound. Needs `max_control_speed`.

    ## Observation Space

    Default: (q, p, u), `Box(-inf, inf, (2n + m,), float32)`; a step taking an entry past float32's range (±3.4e38)
    raises `connenv.core.StepperError`. With a task that has `observation(state)`, its value as float32 (finite, of one
    shape) in its `observation_space` (else an unbounded Box).

    ## Rewards

    Default 0; with `task`, `task.reward(state, next_state)` on the state dicts before and after the step (finite).

    ## Starting State

    Default q = 0, p = 0, u at the midpoint of finite bounds (else 0 clipped into them), t = 0, or any of them from
    `task.reset(np_random)`'s state dict. `reset(options={"state": {...}})` sets any exactly (a number stands for a
    vector of one entry; within ±1e3, beyond which a user's system may outrun any stepper):

    ## Episode End

    Default: never terminates; with `task`, when `task.terminated(state)`. `info["is_success"]` is
    `task.is_success(state)` if the task has it, else False (an end is not always a success). The registration truncates
    after 1000 steps (`gym.make("connenv/ActiveConstraint-v0", max_episode_steps=...)` changes it).

    ## Arguments

    | kwarg | default | range |
    |---|---|---|
    | system | required | n, m, metric, potential (above) |
    | u_low, u_high | required | numbers or m of them, u_low < u_high, within ±1e3; ±inf allowed (velocity control) |
    | dt | 0.05 | [1e-12, 1] s |
    | control | by jump_class (above) | "position", "velocity" |
    | max_control_speed | None | None or (0, 1e3], per unit of u per second |
    | integrator | below | "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau" |
    | substeps / rtol, atol | | the stepper's |
    | task | None | an object with reset, reward, terminated and optionally observation, is_success (above) |
    | draw | None | `draw(state, canvas)`: draws a state dict on a `connenv.rendering.Canvas` |
    | render_mode | None | "human", "rgb_array" |

    The default integrator is "exact" for a system with a closed-form step (`exact_segment(y, u, u̇, τ)` at constant u̇,
    or `exact_flow(y, u, τ)` where u is held), else DOP853 at rtol 1e-10, atol 1e-12, adapting to a generic system's
    unknown time scales (`python -m connenv.bench generic` compares the candidates). Diverged: an energy error
    (of E = ½ pᵀ A p + V) past 1e-2 (1 + |E|), or a segment needing more evaluations of the vector field than its
    budget, 1000 on a numerical gradient of H (scipy.differentiate), 100 000 on a system's own `vector_field` (exact and
    faster; `from_lagrangian` gives one), so a stall (say, where the metric turns singular ahead) fails in seconds.

    The system's functions are tried at construction, at the samples of (q, u) deciding its class: one raising or
    returning no real numbers, the wrong shape or non-finite values is a ValueError or TypeError naming it. Every `info`
    has `"state"`: `{"q": array(n), "p": array(n), "u": array(m), "t": float}`, and `"is_success"`. A `task`'s methods
    take such state dicts, row by row in the vector env; `connenv.envs.user_task` checks them (at construction: without
    reset, reward and terminated, a TypeError) and every answer, naming the method. docs/guides/own-system.md gives one
    (a rotor turns a body to a target angle).
    """

    renderer = CoordinatePlot

    JAX_NEEDS = (
        "the system's metric, potential and vector_field must take JAX arrays: a system from from_lagrangian "
        "(LagrangianSystem, lambdified to JAX as well) does; a system of your own writes them with the namespace of "
        "their arguments (connenv.core.backend.namespace) and gives vector_field (H's numerical gradient does not "
        "trace); a fit system's jumps (control='position' without max_control_speed) run scipy's DOP853 and do not "
        "trace; a task's methods take Python numbers and do not trace (task=None)"
    )
    """What ``connenv.jax.make`` needs of the user's system to trace this builder (its TypeError otherwise)."""

    STATE = Fields(
        vector("q", "n", about="the free coordinates", bound=MAGNITUDE_BOUND, scalar=True),
        vector("p", "n", about="their conjugate momenta", bound=MAGNITUDE_BOUND, scalar=True),
        vector("u", "m", about="the assigned coordinates", scalar=True, **within("u_low", "u_high", MAGNITUDE_BOUND)),
    )

    def __init__(self, system=None, u_low=None, u_high=None, *, dt: float = 0.05, control: str | None = None,
                 max_control_speed: float | None = None, integrator: str | None = None, task=None,
                 render_mode: str | None = None, draw=None, **stepper_options):
        super().__init__(render_mode, check_dt(dt, DT_MAX))
        check_system(system)
        self.system, self.n, self.m = system, int(system.n), int(system.m)
        self.u_low, self.u_high = check_bounds("u_low", u_low, "u_high", u_high, self.m)
        self.max_control_speed = (
            None
            if max_control_speed is None
            else check_number("max_control_speed", max_control_speed, 0.0, MAGNITUDE_BOUND, open_low=True)
        )
        finite = np.isfinite(self.u_low) & np.isfinite(self.u_high)
        midpoint = 0.5 * (np.where(finite, self.u_low, 0.0) + np.where(finite, self.u_high, 0.0))
        self.u_start = np.where(finite, midpoint, np.clip(0.0, self.u_low, self.u_high))
        q_samples, u_samples = self._samples()
        try:
            check_metric(system, q_samples, u_samples)
            check_fields(system, q_samples, u_samples)
        except (TypeError, ValueError) as error:  # u is sampled within [u_low, u_high], which may hold the fault
            bounds = f"u_low={self.u_low.tolist()}, u_high={self.u_high.tolist()}"
            raise type(error)(f"{error}; u sampled within {bounds}") from error
        self.jump_class = getattr(system, "jump_class", None) or classify(system, q_samples, u_samples)
        self.control = self._check_control(control)
        self.field = system if hasattr(system, "vector_field") else MetricField(system)
        check_stepper_options(self.name, stepper_options, type(self))
        default = "exact" if isinstance(self.field, (ExactSegment, ExactFlow)) else "dop853"
        self.stepper = make_stepper(integrator or default, self.field, **stepper_options)
        self.jump = JumpFlow(system)
        self.adopt(task, draw, ("q", "p", "u"))
        self.action_space = spaces.Box(-1.0, 1.0, (self.m,), np.float32)
        self.state = self.at(np.zeros(2 * self.n), self.u_start.copy(), 0.0, 0.0)
        self.observation_space = self._observation_space()

    @classmethod
    def from_lagrangian(cls, kinetic, potential, q, u, **kwargs):
        """The env of kinetic energy T, potential V, sympy expressions in the Symbol lists q, u and their velocities
        (named s.name + "_dot" for a coordinate s; connenv.core.lagrangian.LagrangianSystem); kwargs: the env's."""
        from connenv.core.lagrangian import LagrangianSystem

        return cls(LagrangianSystem(kinetic, potential, q, u), **kwargs)

    @property
    def components(self) -> dict:
        """The state's names for the model: y = (q₁…qₙ, p₁…pₙ), u = (u₁…uₘ)."""
        n, m = range(1, self.n + 1), range(1, self.m + 1)
        return {"y": (*(f"q{i}" for i in n), *(f"p{i}" for i in n)), "u": tuple(f"u{i}" for i in m)}

    def parameters(self):
        """A declared subclass's physical parameters, else the builder's system and controls."""
        if hasattr(self, "args"):
            return super().parameters()
        return {"system": self.system, "u_low": self.u_low, "u_high": self.u_high, "control": self.control}

    # -- checks ----------------------------------------------------------------

    def _check_control(self, control):
        if control is None:
            control = "velocity" if self.jump_class is JumpClass.GENERAL else "position"
        if control not in CONTROLS:
            raise ValueError(f"control={control!r} is not one of {CONTROLS}")
        if control == "velocity" and self.max_control_speed is None:
            raise ValueError(
                f"control='velocity' (the default for a system of class {self.jump_class.value!r}) needs "
                "max_control_speed: u̇ = action · max_control_speed"
            )
        if control == "position":
            if self.jump_class is JumpClass.GENERAL and self.max_control_speed is None:
                raise ValueError(
                    f"control='position' without max_control_speed would jump u, which a system of class "
                    f"{self.jump_class.value!r} (∂B/∂q ≠ 0) does not admit: give max_control_speed (u ramps to the "
                    "command) or use control='velocity' (the default for this class)"
                )
            if not (np.all(np.isfinite(self.u_low)) and np.all(np.isfinite(self.u_high))):
                raise ValueError(
                    f"control='position' maps the action onto [u_low, u_high] = [{self.u_low}, {self.u_high}], which "
                    "needs finite bounds; a coordinate that winds takes control='velocity' with max_control_speed"
                )
        return control

    def _samples(self):
        """The (q, u) at which the metric is checked and, for a system without its own, the class decided."""
        q = np.array([0.0, 0.5, -0.5])[:, None] * np.ones(self.n)
        low = np.where(np.isfinite(self.u_low), self.u_low, self.u_start - 1.0)
        high = np.where(np.isfinite(self.u_high), self.u_high, self.u_start + 1.0)
        return q, np.stack([self.u_start, low, high, 0.75 * low + 0.25 * high])

    def at(self, y, u, t, energy_error):
        return ActiveConstraintState(y, u, t, energy_error)

    def start(self, options, ops=SCALAR):  # the default start is no draw: the same on JAX's reset (connenv.jax)
        values = self.start_values(options, {"u": self.u_start.copy()})
        return self.at(np.concatenate([values["q"], values["p"]]), values["u"], 0.0, 0.0)

    def command(self, a):
        """The commanded u (position control) or u̇ (velocity control) of action a (one or a batch)."""
        if self.control == "velocity":
            return a * self.max_control_speed
        return self.u_low + 0.5 * (a + 1.0) * (self.u_high - self.u_low)

    def segments(self, u, command, ops=SCALAR):
        """(y's jump or None, control segments, u at the end) of a step from u under the command: one state, or rows,
        each with its own segments where its u stops at a bound."""
        if self.control == "position" and self.max_control_speed is None:
            at_rest = ops.zeros_like(command) if traced(ops) else np.zeros_like(command)  # JAX's rows: no numpy
            return command - u, [(command, at_rest, self.dt)], command
        if self.control == "position":
            xp = ops if traced(ops) else ARRAYS  # JAX's rows (connenv.jax): its one-sided stops, as ARRAYS' at a tie
            u_dot = xp.copysign(self.max_control_speed, command - u)
            low, high = xp.minimum_one_sided(u, command), xp.maximum_one_sided(u, command)
        else:
            u_dot, low, high = command, self.u_low, self.u_high
        cut = bounded_segments if ops is SCALAR else bounded_segments_batch
        segments, u_end, _ = cut(u, u_dot, low, high, self.dt)
        return None, segments, u_end

    def advance(self, s, command, stepper, ops=SCALAR):
        """The state after a step under the command, by this stepper after a fit system's jump: one state, or rows."""
        delta, segments, u_end = self.segments(s.u, command, ops)
        y = s.y
        if delta is not None and self.jump_class is JumpClass.FIT and np.any(delta.real != 0.0):
            y = (JUMP_STEPPER if ops is SCALAR else JUMP_ROWS)(self.jump, y, s.u, delta, 1.0)
        y, change = run_segments(stepper, self.field, y, segments, self.held_energy)
        self.check_energy_error(s.energy_error + change, y, u_end)
        if self.observes_state:
            self.check_observable(y, u_end)
        return self.at(y, u_end, s.t + self.dt, s.energy_error + change)

    def held_energy(self, y, u, u_dot):
        """E = ½ pᵀ A p + V(q, u) where u is held (u̇ = 0, by the real parts on a Jacobian's rows), 0 where u moves."""
        held = np.all(u_dot.real == 0.0, axis=-1)
        if traced(ops := namespace(held)):  # JAX's rows (connenv.jax): every row's E, kept where u is held
            n = self.n
            return ops.where(held, hamiltonian(self.system, y[..., :n], y[..., n:], u, ops.zeros_like(u)), 0.0)
        if not np.any(held):
            return 0.0 if np.ndim(held) == 0 else np.zeros(held.shape)
        n = self.n
        energy = hamiltonian(self.system, y[..., :n], y[..., n:], u, np.zeros_like(u))
        return np.where(held, energy, 0.0) if np.ndim(held) else float(energy)

    def check_energy_error(self, energy_error, y, u):
        n, ops = self.n, namespace(u)
        at_rest = ops.zeros_like(u) if traced(ops) else np.zeros_like(u)  # JAX's rows (connenv.jax): no numpy
        energy = hamiltonian(self.system, y[..., :n], y[..., n:], u, at_rest)
        energy_error, energy = energy_error.real, energy.real
        if traced(ops):  # JAX's rows: the drift traced, a failure as data
            check_drift(self.stepper, "energy error", ops.abs(energy_error) / (1.0 + ops.abs(energy)),
                        ENERGY_ERROR_BOUND)
            return
        check_drift(self.stepper, "energy error", np.abs(energy_error) / (1.0 + np.abs(energy)), ENERGY_ERROR_BOUND)

    @staticmethod
    def check_observable(y, u):
        """StepperError, the state kept, where (q, p) or u (one state or rows) left the observation's float32 range."""
        check_observable("(q, p)", y)
        check_observable("u", u)

    def state_dict(self, s, ops=SCALAR):
        n = self.n
        q, p = s.y[..., :n].copy(), s.y[..., n:].copy()
        u = ops.real(s.u) if traced(ops) else np.array(s.u, float)  # JAX's rows (connenv.jax): no numpy
        return {"q": q, "p": p, "u": u, "t": ops.real(s.t)}

    def raw_observation(self, s):
        """(q, p, u) as float32."""
        return concat([s.y, s.u], axis=-1).astype(np.float32)


SPECS = (
    Spec(
        "connenv/ActiveConstraint-v0", ActiveConstraintEnv, max_episode_steps=1000,
        dt_max=DT_MAX, physics="framework.md", example=examples.swing,
        # the swing at rest at the bottom stays there whatever its radius does: pumping grows a swing, cannot start one
        animation_start={"state": {"q": [0.5]}},
        play="space", space_action=-1.0,
        variants=(examples.swing, examples.rotor, examples.bead),  # one of each jump class
        fast_start={"state": {"p": [1000.0]}},
        bench="generic", jax=(examples.swing_rk4, examples.rotor_ramp_rk4),
    ),
)
