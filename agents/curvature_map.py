"""An env's curvature map (`connenv.geometry.draw`) with the gait its analytic controller runs from reset(seed=0),
as the env pages show it:

    python -m agents.curvature_map ID [--write FILE.png]
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

from agents.controllers import CONTROLLERS, controller
from connenv import cli, geometry
from connenv.envs.spec import spec

PROG = "python -m agents.curvature_map"


def record_gait(env_id: str, field: str) -> tuple[np.ndarray, str]:
    """The shapes (T, k) the env's analytic controller runs through in an episode from reset(seed=0), and the
    legend's words for them; none (0, 2) for an env without a controller."""
    if env_id not in CONTROLLERS:
        return np.zeros((0, 2)), ""
    env = gym.make(env_id, **spec(env_id).make_kwargs())
    policy = controller(env_id, env=env)
    observation, _ = env.reset(seed=0)
    shapes, done = [np.array(getattr(env.unwrapped.state, field), float)], False
    while not done:
        observation, _, terminated, truncated, _ = env.step(policy.predict(observation, deterministic=True)[0])
        shapes.append(np.array(getattr(env.unwrapped.state, field), float))
        done = terminated or truncated
    env.close()
    return np.stack(shapes), f"analytic gait ({spec(env_id).controllers[0]}, reset(seed=0))"


def draw(env_id: str, path: str):
    """The curvature map of the env with its analytic controller's gait, written to path (PNG)."""
    field = geometry.local_connection(env_id).field
    gait, label = record_gait(env_id, field)
    geometry.draw(env_id, path, gait=gait, gait_label=label)


def main(argv: list[str] | None = None):
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("env_id", metavar="ID", help="a connenv id whose env has a mechanical connection")
    parser.add_argument("--write", type=cli.writable_file, metavar="FILE.png",
                        help="where the curvature map goes (default: <Env>-curvature.png here)")  # fmt: skip
    args = parser.parse_args(argv)
    path = args.write or geometry.map_path(args.env_id)
    draw(args.env_id, path)
    print(path)
    return path


if __name__ == "__main__":
    cli.run(main, PROG)
