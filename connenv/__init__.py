"""connenv: Gymnasium environments for mechanical systems steered by active constraints and mechanical connections."""

from gymnasium.envs.registration import register

__version__ = "0.1.0"

register(id="connenv/Swing-v0", entry_point="connenv.envs.swing:SwingEnv", max_episode_steps=500)
register(id="connenv/Skier-v0", entry_point="connenv.envs.skier:SkierEnv", max_episode_steps=1000)
register(id="connenv/RollingBall-v0", entry_point="connenv.envs.rolling_ball:RollingBallEnv", max_episode_steps=200)
register(id="connenv/RollingBallPose-v0", entry_point="connenv.envs.rolling_ball:RollingBallPoseEnv", max_episode_steps=300)
register(id="connenv/RollingBallGoal-v0", entry_point="connenv.envs.rolling_ball:RollingBallGoalEnv", max_episode_steps=200)
register(id="connenv/KozlovShell-v0", entry_point="connenv.envs.kozlov_shell:KozlovShellEnv", max_episode_steps=300)
register(id="connenv/KapitzaPendulum-v0", entry_point="connenv.envs.kapitza:KapitzaPendulumEnv", max_episode_steps=2000)
register(id="connenv/KapitzaSwingUp-v0", entry_point="connenv.envs.kapitza:KapitzaSwingUpEnv", max_episode_steps=6000)
