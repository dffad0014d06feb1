"""One `Spec` per env id, declared beside its classes as the module's ``SPECS``: what connenv knows of an id beyond
Gymnasium's registration. ``import connenv`` registers every id with Gymnasium from `connenv.envs.ids`, a table
generated from the specs (``python -m connenv.envs.spec`` writes it; a test checks it), so that the import loads no
env module, no scipy and no sympy; `registry` finds every module of connenv.envs that declares SPECS on first use
(`discover`). The docs site's map, the baseline tables, the analytic controllers' registry
(agents.controllers) and the test tables (contract, fuzz, hardening, golden, audit) are read off `registry`, so that
adding an env is writing its own files, and the table regenerated (docs/guides/new-env.md).

Gymnasium's registry stays the source users see: ``gym.make("connenv/Name-v0")`` and
``gym.make_vec(..., vectorization_mode="vector_entry_point")`` read the `gymnasium.envs.registration.EnvSpec` that
`register` makes of a Spec (id, entry points, max_episode_steps, kwargs).
"""

from __future__ import annotations

import importlib
import pkgutil
import pprint
import sys
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path

from gymnasium.envs.registration import register as gym_register

from connenv.envs.vector import TaskVectorEnv, vector_env


class Registry(MutableMapping):
    """{id: Spec} of every connenv id, filled on first use with the SPECS of connenv.envs' modules (`discover`):
    ``import connenv`` registers the ids with Gymnasium from the table `connenv.envs.ids` and imports no env module."""

    def __init__(self):
        self._specs: dict[str, Spec] = {}
        self._found = False

    def _find(self) -> dict[str, Spec]:
        if not self._found:
            self._found = True  # before discover: an env module imported there may read the registry
            try:
                found = discover()
            except BaseException:
                self._found = False  # a module that failed to import: the next read tries again, not a partial table
                raise
            for spec in found:
                self._specs.setdefault(spec.id, spec)
        return self._specs

    def __getitem__(self, env_id: str) -> Spec:
        return self._find()[env_id]

    def __setitem__(self, env_id: str, spec: Spec):
        self._find()[env_id] = spec

    def __delitem__(self, env_id: str):
        del self._find()[env_id]

    def __iter__(self) -> Iterator[str]:
        return iter(self._find())

    def __len__(self) -> int:
        return len(self._find())

    def __repr__(self) -> str:
        return f"Registry({list(self)})"


registry = Registry()
"""Every registered connenv id's Spec, in registration order (the modules' alphabetical order, then each module's)."""

_first_spec: dict[type, str] = {}  # an env class's first id's name, which names the class (Spec.__post_init__)


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
    tests, or a function making them, as ``variants``' (a builder's example); empty: no JAX version yet, and
    ``connenv.jax.make`` refuses the id).
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
    jax: tuple[KwargsOrMaker, ...] = ()
    vector_base: type = TaskVectorEnv
    vector_env: type = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "vector_env", vector_env(self.env, self.vector_base))
        # the env class's name, which its errors call it by, set as its module declares SPECS: its first id's
        # name, or their stem ("BeadOnBar") where the class is registered as several versions
        first = _first_spec.setdefault(self.env, self.name)
        if first == self.name:
            self.env.name = self.name
        elif first.rpartition("-v")[0] == self.name.rpartition("-v")[0]:
            self.env.name = self.name.rpartition("-v")[0]

    @property
    def name(self) -> str:
        """The id without its namespace, "Name-v0": how pages, files and error messages name the env."""
        return self.id.split("/", 1)[1]

    def make_kwargs(self) -> dict:
        """The kwargs the id is made with where nothing else is asked: its example's, or none."""
        return self.example() if self.example else {}


def entry_point(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def registration(spec: Spec) -> dict:
    """Gymnasium's registration of a spec: the keyword arguments of gymnasium.register."""
    return {
        "id": spec.id, "entry_point": entry_point(spec.env), "vector_entry_point": entry_point(spec.vector_env),
        "max_episode_steps": spec.max_episode_steps, "kwargs": dict(spec.kwargs),
    }  # fmt: skip


def register(*specs: Spec):
    """Register each spec with Gymnasium and in `registry` (the ids of a package other than connenv.envs, such as a
    user's own: connenv's are registered by ``import connenv``)."""
    for spec in specs:
        gym_register(**registration(spec))
        registry[spec.id] = spec


def discover(package: str = "connenv.envs") -> list[Spec]:
    """The SPECS of every module of the package, in the modules' alphabetical order."""
    found = []
    for module in pkgutil.iter_modules(importlib.import_module(package).__path__):
        found += getattr(importlib.import_module(f"{package}.{module.name}"), "SPECS", ())
    return found


IDS_PATH = Path(__file__).with_name("ids.py")


def ids_source() -> str:
    """The text of connenv/envs/ids.py: Gymnasium's registration of every spec of connenv.envs."""
    table = pprint.pformat([registration(spec) for spec in discover()], width=120, sort_dicts=False)
    return (
        '"""Gymnasium\'s registration of every connenv id, which ``import connenv`` reads (it imports no env module).\n'
        "Generated from the specs by ``python -m connenv.envs.spec``; tests/test_imports.py checks it. Do not edit.\n"
        '"""\n\n'
        f"IDS = {table}\n"
    )


def spec(env_id: str) -> Spec:
    """The Spec of a registered connenv id (KeyError naming the known ids otherwise)."""
    try:
        return registry[env_id]
    except KeyError:
        raise KeyError(f"{env_id!r} is no registered connenv id; known: {sorted(registry)}") from None


if __name__ == "__main__":  # python -m connenv.envs.spec: write connenv/envs/ids.py from the specs
    from connenv.envs import spec as specs  # the module the env modules' specs are made by, not this __main__

    specs.IDS_PATH.write_text(specs.ids_source())
    sys.stdout.write(f"wrote {specs.IDS_PATH}\n")
