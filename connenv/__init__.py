"""connenv: Gymnasium environments for mechanical systems steered by active constraints and mechanical connections."""

from gymnasium.envs.registration import register as _register

from connenv.envs.ids import IDS as _IDS

__version__ = "0.3.0"
__all__ = ["ActiveConstraintEnv", "ConnectionEnv"]


def __getattr__(name):
    """connenv.ActiveConstraintEnv and connenv.ConnectionEnv."""
    if name == "ActiveConstraintEnv":
        from connenv.envs.active_constraint import ActiveConstraintEnv

        return ActiveConstraintEnv
    if name == "ConnectionEnv":
        from connenv.envs.connection import ConnectionEnv

        return ConnectionEnv
    raise AttributeError(f"module 'connenv' has no attribute {name!r}")


for _registration in _IDS:  # every id declared by a module of connenv.envs (its SPECS), from the table made of them
    _register(**_registration)
del _registration
