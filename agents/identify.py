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
from connenv.core.steppers import StepperError


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


def starting_values(model, names: list[str], env_id: str) -> np.ndarray:
    """The model's values of the parameters `names`, where the fit starts: each a positive number, else a ValueError
    naming it (a parameter that is None at the make values, as an unlimited speed, has no scale to fit from)."""
    unknown = [name for name in names if not hasattr(model.params, name)]
    if unknown:
        raise ValueError(f"{unknown} are not physical parameters of {env_id}; valid: {sorted(vars(model.params))}")
    values = {name: getattr(model.params, name) for name in names}
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < np.inf:
            raise ValueError(f"{name} is {value!r} at {env_id}'s make values: a fit starts from a positive number")
    return np.array(list(values.values()), float)


def identify(env_id: str, data, names: list[str], **kwargs) -> dict:
    """The parameters `names` that best predict the transitions, fitted from the make kwargs' values. A ValueError
    says why where there is no such fit: no state entry changes over the data, the prediction does not change with
    some parameter (or with some combination of them), the fit did not converge, or the model at other values
    rejects the recorded states (their invariant checks hold a quantity of the true values, as an energy at reset)."""
    x, a, x_next = data
    model = gym.make(env_id, **kwargs).unwrapped.model
    spread = np.sqrt(np.mean((x_next - x) ** 2, axis=0))  # root mean square: one transition is data too
    moving = spread > 1e-10 * np.maximum(np.max(np.abs(x), axis=0), 1.0)  # not a clock's, nor a rounding error's
    real = moving & np.array([e.real and e.name != "t" for e in model.entries for _ in range(e.size)])
    if not real.any():
        raise ValueError(f"no state entry of {env_id} changes over the {len(x)} transitions: nothing to fit "
                         f"{', '.join(names)} to; record more (--steps)")  # fmt: skip
    scale = spread[real]
    start = np.log(starting_values(model, names, env_id))
    tried = start

    def residuals(log_theta):
        nonlocal tried
        tried = log_theta
        predicted = model.step(x, a, params=dict(zip(names, np.exp(log_theta).tolist())))
        return ((predicted - x_next)[:, real] / scale).ravel()

    try:
        fit = least_squares(residuals, start, diff_step=1e-6, xtol=1e-12, ftol=1e-12)
    except StepperError as error:
        at = ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, np.exp(tried)))
        where = " (the make values, where the fit starts)" if np.array_equal(tried, start) else ""
        raise ValueError(
            f"{', '.join(names)} cannot be identified on {env_id} by one-step prediction: the model at {at}{where} "
            f"rejects the states recorded with the true values ({error})"
        ) from error
    if not fit.success:
        raise ValueError(f"the fit of {', '.join(names)} on {env_id} did not converge: {fit.message}")
    columns = np.linalg.norm(fit.jac, axis=0)
    singular = np.linalg.svd(fit.jac, compute_uv=False)
    if fit.jac.shape[0] < len(names) or singular.min() <= 1e-8 * singular.max():
        inert = [name for name, norm in zip(names, columns) if norm <= 1e-8 * columns.max()]
        why = (f"the predicted step does not change with {', '.join(inert)}" if inert
               else "the predicted step changes with them only together")  # fmt: skip
        raise ValueError(f"{len(x)} transitions of {env_id} do not determine {', '.join(names)}: {why}; record "
                         "more (--steps) or fit fewer")  # fmt: skip
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
    starting_values(gym.make(args.env).unwrapped.model, list(true), args.env)  # before the data are recorded
    fitted = identify(args.env, transitions(args.env, true, args.steps, args.seed), list(true))
    for name, value in fitted.items():
        print(f"{name}: true {true[name]:.6g}, fitted {value:.6g}, error {value / true[name] - 1:+.2e}")
    return fitted


if __name__ == "__main__":
    cli.run(main, PROG)
