"""The specs of the two builders, ActiveConstraint-v0 and Connection-v0, made with connenv.examples' worked systems.

They belong beside their classes in active_constraint.py and connection.py, and move there once those modules are
free to edit (issue 32: the builders' vector physics is being rewritten in the meantime)."""

from __future__ import annotations

from connenv import examples
from connenv.envs.active_constraint import DT_MAX as ACTIVE_CONSTRAINT_DT_MAX
from connenv.envs.active_constraint import ActiveConstraintEnv, ActiveConstraintVectorEnv
from connenv.envs.connection import DT_MAX as CONNECTION_DT_MAX
from connenv.envs.connection import ConnectionEnv, ConnectionVectorEnv
from connenv.envs.spec import Spec

SPECS = (
    Spec(
        "connenv/ActiveConstraint-v0", ActiveConstraintEnv, ActiveConstraintVectorEnv, max_episode_steps=1000,
        dt_max=ACTIVE_CONSTRAINT_DT_MAX, physics="framework.md", example=examples.swing,
        # the swing at rest at the bottom stays there whatever its radius does: pumping grows a swing, cannot start one
        animation_start={"state": {"q": [0.5]}},
        play="space", space_action=-1.0,
        variants=(examples.swing, examples.rotor, examples.bead),  # one of each jump class
        state_keys={"q": 1, "p": 1, "u": 1},  # examples.swing(): n = m = 1
        fast_start={"state": {"p": [1000.0]}},
        bench="generic",
    ),
    Spec(
        "connenv/Connection-v0", ConnectionEnv, ConnectionVectorEnv, max_episode_steps=1000, dt_max=CONNECTION_DT_MAX,
        physics="connections.md", example=examples.beanie,
        variants=(examples.beanie, examples.rolling_ball),  # a flat and a curved connection
        state_keys={"s": 1},  # examples.beanie(): k = 1
        fast_start={"state": {"s": [1000.0]}},
        bench="connection",
    ),
)
