"""Train an agent with rl-zoo3, then compare it with the analytic controller and a random policy:

    python train.py --env ID --algo ppo --timesteps N --seed 0    # ID: a connenv id (--help lists them)

The command of ``agents.train``, whose docstring (and ``python train.py --help``) says what a run does and leaves.
"""

from agents.train import PROG, main
from connenv import cli

if __name__ == "__main__":
    cli.run(main, PROG)
