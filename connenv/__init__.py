"""connenv: Gymnasium environments for mechanical systems steered by active constraints and mechanical connections."""

from gymnasium.envs.registration import register

__version__ = "0.3.0"
__all__ = ["ActiveConstraintEnv", "ConnectionEnv"]


def __getattr__(name):
    """connenv.ActiveConstraintEnv and connenv.ConnectionEnv, imported on first use (``import connenv`` stays
    light: no sympy)."""
    if name == "ActiveConstraintEnv":
        from connenv.envs.active_constraint import ActiveConstraintEnv

        return ActiveConstraintEnv
    if name == "ConnectionEnv":
        from connenv.envs.connection import ConnectionEnv

        return ConnectionEnv
    raise AttributeError(f"module 'connenv' has no attribute {name!r}")


register(
    id="connenv/Swing-v0",
    entry_point="connenv.envs.swing:SwingEnv",
    vector_entry_point="connenv.envs.swing:SwingVectorEnv",
    max_episode_steps=500,
)
register(
    id="connenv/Skier-v0",
    entry_point="connenv.envs.skier:SkierEnv",
    vector_entry_point="connenv.envs.skier:SkierVectorEnv",
    max_episode_steps=1000,
)
register(
    id="connenv/RollingBall-v0",
    entry_point="connenv.envs.rolling_ball:RollingBallEnv",
    vector_entry_point="connenv.envs.rolling_ball:RollingBallVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/RollingBallPose-v0",
    entry_point="connenv.envs.rolling_ball:RollingBallPoseEnv",
    vector_entry_point="connenv.envs.rolling_ball:RollingBallPoseVectorEnv",
    max_episode_steps=300,
)
register(
    id="connenv/RollingBallGoal-v0",
    entry_point="connenv.envs.rolling_ball:RollingBallGoalEnv",
    vector_entry_point="connenv.envs.rolling_ball:RollingBallGoalVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/KozlovShell-v0",
    entry_point="connenv.envs.kozlov_shell:KozlovShellEnv",
    vector_entry_point="connenv.envs.kozlov_shell:KozlovShellVectorEnv",
    max_episode_steps=300,
)
register(
    id="connenv/SnakeSwimmer-v0",
    entry_point="connenv.envs.snake_swimmer:SnakeSwimmerEnv",
    vector_entry_point="connenv.envs.snake_swimmer:SnakeSwimmerVectorEnv",
    max_episode_steps=1000,
)
register(
    id="connenv/KapitzaPendulum-v0",
    entry_point="connenv.envs.kapitza:KapitzaPendulumEnv",
    vector_entry_point="connenv.envs.kapitza:KapitzaPendulumVectorEnv",
    max_episode_steps=2000,
)
register(
    id="connenv/KapitzaSwingUp-v0",
    entry_point="connenv.envs.kapitza:KapitzaSwingUpEnv",
    vector_entry_point="connenv.envs.kapitza:KapitzaSwingUpVectorEnv",
    max_episode_steps=6000,
)
register(
    id="connenv/RollingCoinSurface-v0",
    entry_point="connenv.envs.rolling_coin_surface:RollingCoinSurfaceEnv",
    vector_entry_point="connenv.envs.rolling_coin_surface:RollingCoinSurfaceVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/BeadOnBar-v0",
    entry_point="connenv.envs.bead_on_bar:BeadOnBarEnv",
    vector_entry_point="connenv.envs.bead_on_bar:BeadOnBarVectorEnv",
    max_episode_steps=500,
)
register(  # v1: the bar turns at most 1 rad/s (BeadOnBarEnv's Version History)
    id="connenv/BeadOnBar-v1",
    entry_point="connenv.envs.bead_on_bar:BeadOnBarEnv",
    vector_entry_point="connenv.envs.bead_on_bar:BeadOnBarVectorEnv",
    max_episode_steps=500,
    kwargs={"omega_max": 1.0},
)
register(
    id="connenv/ChaplyginSleigh-v0",
    entry_point="connenv.envs.chaplygin_sleigh:ChaplyginSleighEnv",
    vector_entry_point="connenv.envs.chaplygin_sleigh:ChaplyginSleighVectorEnv",
    max_episode_steps=1000,
)
register(
    id="connenv/ActiveConstraint-v0",
    entry_point="connenv.envs.active_constraint:ActiveConstraintEnv",
    vector_entry_point="connenv.envs.active_constraint:ActiveConstraintVectorEnv",
    max_episode_steps=1000,
)
register(
    id="connenv/Connection-v0",
    entry_point="connenv.envs.connection:ConnectionEnv",
    vector_entry_point="connenv.envs.connection:ConnectionVectorEnv",
    max_episode_steps=1000,
)
register(
    id="connenv/RollingCoin-v0",
    entry_point="connenv.envs.rolling_coin:RollingCoinEnv",
    vector_entry_point="connenv.envs.rolling_coin:RollingCoinVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/ElroysBeanie-v0",
    entry_point="connenv.envs.elroys_beanie:ElroysBeanieEnv",
    vector_entry_point="connenv.envs.elroys_beanie:ElroysBeanieVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/TubeTwist-v0",
    entry_point="connenv.envs.tube:TubeTwistEnv",
    vector_entry_point="connenv.envs.tube:TubeTwistVectorEnv",
    max_episode_steps=200,
)
register(
    id="connenv/FallingCat-v0",
    entry_point="connenv.envs.falling_cat:FallingCatEnv",
    vector_entry_point="connenv.envs.falling_cat:FallingCatVectorEnv",
    max_episode_steps=60,
)
