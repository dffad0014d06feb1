"""Analytic reference controllers, one module per env module (agents.controllers.swing for connenv.envs.swing).
Each answers SB3's ``predict(obs, deterministic=True) -> (action, state)``, so the evaluation treats an analytic law
and a trained network alike; observations may be batched. A controller's name in an env's spec
(``Spec.controllers``) is a function ``name(env)`` of its module: a factory of the unwrapped env, for the parameters
a law needs."""

from __future__ import annotations

import importlib

import connenv  # noqa: F401  (registers the envs)
from connenv.envs.spec import Spec, registry


def module_of(spec: Spec):
    """agents.controllers.<name> for an env class in a module <name>."""
    return importlib.import_module(f"{__name__}.{spec.env.__module__.rsplit('.', 1)[-1]}")


CONTROLLERS = {
    spec.id: {name: getattr(module_of(spec), name) for name in spec.controllers}
    for spec in registry.values()
    if spec.controllers
}
"""Reference controllers by env id and name, from the specs: a factory of the unwrapped env."""


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
