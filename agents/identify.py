"""System identification on the model: recover an env's physical parameters from recorded transitions.

    python -m agents.identify --env ID --true NAME=VALUE ... --steps 1000    # e.g. g=7.3 mass=1.8

The transitions (x, a, x′) are the env's own steps under a random policy, x the model's state vector
(``env.unwrapped.model``). The fit is ``scipy.optimize.least_squares`` on the one-step prediction error
model.step(x, a; θ) − x′ over all of them at once (one batched step per evaluation), each state entry scaled by the
spread of its change over the data (the entries that change beyond rounding: no clock, no error
accumulator), in log θ (the parameters are scales: positive, of unknown magnitude). Its
derivatives in θ are least_squares' differences: the model's Jacobians are in x and a, and a parameter enters the
step through the env's construction (a trail, a closed-form flow), not as an input to differentiate.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from scipy.optimize import least_squares

import connenv  # noqa: F401  (registers the envs)
from connenv import cli


def transitions(env_id: str, params: dict, steps: int, seed: int = 0, **kwargs):
    """(x, a, x′) of `steps` random-policy steps of the env with these parameters, reset on termination."""
    env = gym.make(env_id, **kwargs).unwrapped
    env.action_space.seed(seed)
    env.reset(seed=seed, options={"params": params})
    model = env.model
    xs, actions, nexts = [], [], []
    for i in range(steps):
        a = env.action_space.sample()
        xs.append(model.pack(env.state))
        _, _, terminated, _, _ = env.step(a)
        actions.append(a)
        nexts.append(model.pack(env.state))
        if terminated:
            env.reset(seed=seed + i + 1, options={"params": params})
    return np.array(xs), np.array(actions, float), np.array(nexts)


def identify(env_id: str, data, names: list[str], **kwargs) -> dict:
    """The parameters `names` that best predict the transitions, fitted from the make kwargs' values."""
    x, a, x_next = data
    model = gym.make(env_id, **kwargs).unwrapped.model
    spread = np.std(x_next - x, axis=0)
    moving = spread > 1e-10 * np.maximum(np.max(np.abs(x), axis=0), 1.0)  # not a clock's, nor a rounding error's
    real = moving & np.array([e.real and e.name != "t" for e in model.entries for _ in range(e.size)])
    scale = spread[real]
    start = np.log([getattr(model.params, n) for n in names])

    def residuals(log_theta):
        predicted = model.step(x, a, params=dict(zip(names, np.exp(log_theta).tolist())))
        return ((predicted - x_next)[:, real] / scale).ravel()

    fit = least_squares(residuals, start, diff_step=1e-6, xtol=1e-12, ftol=1e-12)
    return dict(zip(names, np.exp(fit.x).tolist()))


PROG = "python -m agents.identify"


def assignment(text: str) -> tuple[str, float]:
    """argparse type: NAME=VALUE with a positive number."""
    name, _, value = text.partition("=")
    return name, cli.parsed(value, float, lambda v: v > 0, f"a positive number in {text!r} (NAME=VALUE)")


def main(argv: list[str] | None = None) -> dict:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", required=True, choices=sorted(i for i in gym.registry if i.startswith("connenv/")))
    parser.add_argument("--true", nargs="+", required=True, metavar="NAME=VALUE", type=assignment,
                        help="the parameters the data are made with; these are then fitted")
    parser.add_argument("--steps", type=cli.positive_int, default=1000)
    parser.add_argument("--seed", type=cli.seed_int, default=0)
    args = parser.parse_args(argv)
    true = dict(args.true)
    fitted = identify(args.env, transitions(args.env, true, args.steps, args.seed), list(true))
    for name, value in fitted.items():
        print(f"{name}: true {true[name]:.6g}, fitted {value:.6g}, error {value / true[name] - 1:+.2e}")
    return fitted


if __name__ == "__main__":
    cli.run(main, PROG)
