"""One `Spec` per env id, declared beside its classes as the module's ``SPECS``: what connenv knows of an id beyond
Gymnasium's registration. ``import connenv`` finds every module of connenv.envs that declares SPECS and registers
each spec (`register`); the docs site's map, the baseline tables, the analytic controllers' registry
(agents.controllers) and the test tables (contract, fuzz, hardening, golden, audit) are read off `registry`, so that
adding an env is writing its own files (docs/guides/new-env.md).

Gymnasium's registry stays the source users see: ``gym.make("connenv/Name-v0")`` and
``gym.make_vec(..., vectorization_mode="vector_entry_point")`` read the `gymnasium.envs.registration.EnvSpec` that
`register` makes of a Spec (id, entry points, max_episode_steps, kwargs).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field

from gymnasium.envs.registration import register as gym_register

from connenv.envs.vector import TaskVectorEnv, vector_env

registry: dict[str, Spec] = {}
"""Every registered connenv id's Spec, in registration order (the modules' alphabetical order, then each module's)."""


@dataclass(frozen=True)
class Measure:
    """The reference table's physical measure of an env (agents.baselines): its label, its unit, and the statistic
    of agents.evaluate's summary it reads: "time_to_success" (the mean time of the successful episodes),
    "steps_to_target" (their mean length), or a key of the episodes' ``info["measures"]`` (its mean)."""

    label: str
    unit: str
    statistic: str


KwargsOrMaker = dict | Callable[[], dict]
"""Make kwargs, or a function that makes them (kwargs that are costly to build, such as a sympy system)."""


@dataclass(frozen=True)
class Spec:
    """An env id and everything about it that tools and tests read.

    Registration (Gymnasium's EnvSpec): ``id`` ("connenv/Name-vN"), ``env`` (the single env's class),
    ``max_episode_steps``, ``kwargs`` (the id's make kwargs: a later version may be the same class with other kwargs);
    the spec makes the native vector env, ``vector_env`` (`connenv.envs.vector.vector_env`, of ``vector_base`` where
    the env's vector env adds to TaskVectorEnv's). Both register as "module:Class" entry points.

    The env: ``dt_max`` (s, the longest dt its make kwargs take, documented in its Arguments table); ``physics``
    (its physics page under docs/physics/); ``example`` (make kwargs for an id that cannot be made without them: the
    builders' worked systems); ``animation_start`` (reset options of the docs' animation).

    Agents: ``measure`` (the reference table's physical measure; None: no row in the table); ``controllers`` (the
    names of its analytic controllers, each a factory ``name(env)`` in ``agents.controllers.<env module>``, the first
    the analytic reference); ``play`` (how ``python -m connenv.play`` sets the action by hand: "arrows", "mouse", or
    "space" with ``space_action`` the action while the space bar is held).

    Tests: ``variants`` (make kwargs worth the contract tests, one code path each), ``starts`` (reset options worth
    them); ``fast_start`` (the fastest reset allowed, where a step of dt_max costs the stepper most); ``golden``
    (golden trajectories: (name, make kwargs with max_episode_steps, reset options)). The bad-input audit reads the
    reset state's and options' keys off the env's declared ``STATE`` and ``OPTIONS`` (`connenv.core.state`).

    Benchmarks: ``bench`` (the key of its cases in connenv.bench's tables); ``single_target`` and
    ``vector_target`` (connenv.throughput's targets, issue 20: the largest ratio of its step time to Pendulum-v1's,
    and the smallest fraction of CartPole-v1's native vector env-steps/s at N = 4096; None: no target).

    JAX: ``jax`` (the make kwargs whose step ``connenv.jax`` traces, each checked against the numpy env in the
    tests; empty: no JAX version yet, and ``connenv.jax.make`` refuses the id).
    """

    id: str
    env: type
    max_episode_steps: int
    dt_max: float
    physics: str
    kwargs: dict = field(default_factory=dict)
    example: Callable[[], dict] | None = None
    animation_start: dict | None = None
    measure: Measure | None = None
    controllers: tuple[str, ...] = ()
    play: str = "arrows"
    space_action: float = 1.0
    variants: tuple[KwargsOrMaker, ...] = ({},)
    starts: tuple[dict | None, ...] = (None,)
    fast_start: dict | None = None
    golden: tuple[tuple[str, dict, dict | None], ...] = ()
    bench: str | None = None
    single_target: float | None = None
    vector_target: float | None = None
    jax: tuple[dict, ...] = ()
    vector_base: type = TaskVectorEnv
    vector_env: type = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "vector_env", vector_env(self.env, self.vector_base))

    @property
    def name(self) -> str:
        """The id without its namespace, "Name-v0": how pages, files and error messages name the env."""
        return self.id.split("/", 1)[1]

    def make_kwargs(self) -> dict:
        """The kwargs the id is made with where nothing else is asked: its example's, or none."""
        return self.example() if self.example else {}


def entry_point(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def register(*specs: Spec):
    """Register each spec with Gymnasium and in `registry`, and name its env class (``name``) after its first id, or
    after their stem ("BeadOnBar") where a class is registered as several versions."""
    for spec in specs:
        gym_register(
            id=spec.id, entry_point=entry_point(spec.env),
            vector_entry_point=entry_point(spec.vector_env),
            max_episode_steps=spec.max_episode_steps, kwargs=dict(spec.kwargs),
        )
        first = next((known for known in registry.values() if known.env is spec.env), None)
        if first is None:
            spec.env.name = spec.name
        elif first.name.rpartition("-v")[0] == spec.name.rpartition("-v")[0]:  # another version: their shared stem
            spec.env.name = spec.name.rpartition("-v")[0]
        registry[spec.id] = spec


def discover(package: str = "connenv.envs") -> list[Spec]:
    """The SPECS of every module of the package, in the modules' alphabetical order."""
    found = []
    for module in pkgutil.iter_modules(importlib.import_module(package).__path__):
        found += getattr(importlib.import_module(f"{package}.{module.name}"), "SPECS", ())
    return found


def spec(env_id: str) -> Spec:
    """The Spec of a registered connenv id (KeyError naming the known ids otherwise)."""
    try:
        return registry[env_id]
    except KeyError:
        raise KeyError(f"{env_id!r} is no registered connenv id; known: {sorted(registry)}") from None
