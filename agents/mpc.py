"""Planners on the env's own model: sampling MPC (MPPI) and iLQR, a reference row that needs no training.

    python -m agents.evaluate --env ID --policy analytic mpc ilqr

Both plan from the env's true state, not its observation: ``env.unwrapped.model`` (connenv.core.model) steps the task
state x = ``model.pack(env.unwrapped.state)`` exactly as the env does, so a plan's predicted return is the return the
env pays if the plan is followed. A planner is bound to the env it drives (``bind``, which agents.evaluate's
run_episode calls before the episode) and re-reads the env's model at each episode's start, since a reset may change
its parameters. Each answers SB3's ``predict(obs, state=None, episode_start=None, deterministic=True)``.

A plan is H knots, each an action held for ``repeat`` steps of the env (the control is piecewise constant on a grid
coarser than dt where dt is short against the task's time scale); the first knot is executed, then the plan is
shifted by one knot and its last knot repeated (the warm start), and optimized again from the state reached. The
return of a rollout is the env's reward summed, as the env pays it, until the step the task terminates (success, or a
failure that ends the episode): nothing past the end counts, so a plan that reaches the target early is not charged
for the time after it. No terminal value is added: the rewards are potential-based (Ng et al. 1999), so a horizon's
return is already the progress of its last state.

Their table beside the analytic controller is agents.planners'.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, fields
from pathlib import Path
from typing import ClassVar

import gymnasium as gym
import numpy as np
import scipy.linalg
import yaml

import connenv  # noqa: F401  (registers the envs)
from connenv import cli
from connenv.envs.spec import registry

PLANNERS = ("mpc", "ilqr")


@dataclass(frozen=True)
class Hyper:
    """A planner's budget. ``samples``: MPPI's rollouts per iteration (K); ``horizon``: knots per plan (H);
    ``repeat``: env steps per knot; ``iterations``: MPPI updates, or iLQR iterations, per control step;
    ``temperature``: MPPI's λ, in units of the spread (std) of the sampled returns, so that one value suits returns of
    any scale; ``noise``: the std of MPPI's perturbations, as a fraction of the action range's half width."""

    samples: int = 64
    horizon: int = 20
    repeat: int = 1
    iterations: int = 1
    temperature: float = 0.5
    noise: float = 0.5

    RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "samples": (2, 100_000), "horizon": (1, 10_000), "repeat": (1, 1_000), "iterations": (1, 1_000),
        "temperature": (1e-6, 1e6), "noise": (1e-6, 10.0),
    }  # fmt: skip

    def __post_init__(self):
        for f in fields(self):
            low, high = self.RANGES[f.name]
            value = getattr(self, f.name)
            if f.type == "int" and value != int(value):
                raise ValueError(f"{f.name}={value!r} is not an integer in [{low:g}, {high:g}]")
            if not low <= value <= high:
                raise ValueError(f"{f.name}={value!r} is outside [{low:g}, {high:g}]")


HYPERPARAMS = Path(__file__).resolve().parent / "hyperparams" / "mpc.yml"
"""The planners' budget per env (Hyper's fields by env id, ``default`` for the others); its comments say why."""


@functools.cache
def budgets() -> dict[str, dict]:
    return yaml.safe_load(HYPERPARAMS.read_text())


def hyper(env_id: str, **overrides) -> Hyper:
    """The env's budget in agents/hyperparams/mpc.yml, with overrides."""
    return Hyper(**{**budgets().get(env_id, budgets()["default"]), **overrides})


class Planner:
    """The shared part of MPPI and iLQR: binding to the env, the knot schedule, the warm start, timing. The plan is
    kept per env step, T = horizon × repeat rows of actions, and optimized again every ``repeat`` steps."""

    def __init__(self, env_id: str, seed: int = 0, **overrides):
        self.env_id, self.hyper = env_id, hyper(env_id, **overrides)
        self.rng = np.random.default_rng(seed)
        self.env = self.model = self.plan = None
        self.plan_seconds: list[float] = []  # wall time of each optimization, for the compute column

    @property
    def steps(self) -> int:
        """T: env steps per plan."""
        return self.hyper.horizon * self.hyper.repeat

    def bind(self, env: gym.Env):
        """Drive env: plan from its true state, with its model (read again at each episode's start)."""
        self.env, self.model = env, None

    def start_episode(self):
        unwrapped = self.env.unwrapped
        self.model, self.plan, self.step_in_knot = unwrapped.model, None, 0
        space = unwrapped.action_space
        self.low, self.high = (
            np.broadcast_to(b, space.shape).reshape(-1).astype(float) for b in (space.low, space.high)
        )

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        if self.env is None:
            raise RuntimeError(f"{type(self).__name__} plans from the env's state: call bind(env) before predict")
        if self.model is None or (episode_start is not None and np.any(episode_start)):
            self.start_episode()
        if self.step_in_knot == 0:
            start = time.perf_counter()
            self.plan = self.optimize(self.model.pack(self.env.unwrapped.state), self.warm_start())
            self.plan_seconds.append(time.perf_counter() - start)
        action = self.plan[self.step_in_knot].reshape(self.env.unwrapped.action_space.shape).astype(np.float32)
        self.step_in_knot = (self.step_in_knot + 1) % self.hyper.repeat
        return action, state

    def warm_start(self) -> np.ndarray:
        """The last plan (T, m) shifted by one knot, its last knot repeated; the range's middle at an episode's
        start."""
        if self.plan is None:
            return np.tile((self.low + self.high) / 2, (self.steps, 1))
        r = self.hyper.repeat
        return np.concatenate([self.plan[r:], self.plan[-r:]])

    @staticmethod
    def ROLLOUTS(h: Hyper) -> int:
        """Rollouts per iteration."""
        raise NotImplementedError

    def optimize(self, x: np.ndarray, U: np.ndarray) -> np.ndarray:
        raise NotImplementedError


def rollout(model, x: np.ndarray, act, T: int):
    """(returns (N,), states (N, T + 1, n), actions (N, T, m), alive (N, T)) of the rows' plans from x through
    model.step, act(t, X) giving the rows' actions (N, m) at step t from their states X; a row's reward counts until
    the step after which it terminates, and ``alive[:, t]`` says whether step t counts."""
    X = x[None] if x.ndim == 1 else x
    states, actions, alive = [X], [], []
    total, live = np.zeros(len(X)), np.ones(len(X), bool)
    for t in range(T):
        a = act(t, X)
        X_next = model.step(X, a)
        alive.append(live.copy())
        total += np.where(live, model.reward(X, a, X_next), 0.0)
        live &= ~np.asarray(model.terminated(X_next), bool)
        X = X_next
        states.append(X)
        actions.append(a)
    return total, np.stack(states, axis=1), np.stack(actions, axis=1), np.stack(alive, axis=1)


class MPPI(Planner):
    """Model predictive path integral control (Williams, Aldrich & Theodorou, J. Guid. Control Dyn. 2017): K plans
    perturbed by Gaussian noise about the current plan (one draw per knot) are rolled out on the model's rows, and the
    plan moves to their average weighted by exp(return/λ), a soft-max over returns that needs no gradient, so it
    plans through the clips, end stops and switching surfaces where the Jacobians are one-sided. The unperturbed plan
    is one of the K, so that an update never loses the warm start's return by sampling alone."""

    @staticmethod
    def ROLLOUTS(h):
        return h.samples

    def optimize(self, x, U):
        h = self.hyper
        half = (self.high - self.low) / 2
        for _ in range(h.iterations):
            noise = self.rng.standard_normal((h.samples, h.horizon, U.shape[1])) * (h.noise * half)
            noise[0] = 0.0
            candidates = np.clip(U + np.repeat(noise, h.repeat, axis=1), self.low, self.high)
            R = rollout(
                self.model, np.repeat(x[None], h.samples, axis=0), lambda t, X, C=candidates: C[:, t], self.steps
            )[0]
            weights = np.exp((R - R.max()) / (h.temperature * max(float(R.std()), 1e-12)))
            U = np.tensordot(weights / weights.sum(), candidates, axes=1)
        return U


class ILQR(Planner):
    """Iterative LQR (Li & Todorov 2004; Tassa, Erez & Todorov 2012): the dynamics linearized along the plan's
    trajectory by ``model.jacobians`` (complex step, one batched call on the T steps' rows), the reward modelled to
    second order, a backward Riccati pass for the feedforward and feedback gains, and a forward pass of the closed loop
    tried at several step sizes α at once (rows of one rollout: the line search), kept if it raises the return.

    The cost is the env's own reward, not a hand-written quadratic: its derivatives in z = (x, x′), the states before
    and after a step, are central finite differences of ``model.reward`` (cheap: no step), composed with (A, B) to
    first order in the dynamics (Gauss-Newton: the dynamics' second derivatives are left out, as iLQR does).
    Regularization μ is subtracted from Q_uu (Levenberg-Marquardt, Tassa et al. 2012): raised when Q_uu − μI is not
    negative definite or no step size improves, lowered after a success. The gains are per env step; actions are
    clipped to the action space in the forward pass, where the model's B is 0 for a clipped entry."""

    ALPHAS = 0.5 ** np.arange(8)  # the line search's step sizes
    MU_MIN, MU_MAX = 1e-6, 1e10
    FD_STEP = 1e-4  # relative: the fourth root of the rounding, where a second difference's errors balance

    @staticmethod
    def ROLLOUTS(h):
        return 1 + len(ILQR.ALPHAS)  # the trajectory, and the line search's

    def start_episode(self):
        super().start_episode()
        self.mu = 1.0
        self.real = np.array([e.real for e in self.model.entries for _ in range(e.size)])

    def optimize(self, x, U):
        for _ in range(self.hyper.iterations):
            U = self.iterate(x, U)
        return U

    def iterate(self, x, U):
        """One iLQR iteration from plan U (T, m): backward pass, then the line search; U itself if none improves."""
        R, X, _, alive = rollout(self.model, x, lambda t, X: U[None, t], self.steps)
        X, alive = X[0], alive[0]
        A, B = self.model.jacobians(X[:-1], U)
        gains = self.backward(A, B, *self.reward_derivatives(X[:-1], U, X[1:], alive))
        if gains is None:
            self.mu = min(self.mu * 10, self.MU_MAX)
            return U
        returns, trials = self.forward(x, X, U, *gains)
        best = int(np.argmax(returns))
        if returns[best] <= R[0]:
            self.mu = min(self.mu * 10, self.MU_MAX)
            return U
        self.mu = max(self.mu / 2, self.MU_MIN)
        return trials[best]

    def reward_derivatives(self, X, U, X_next, alive):
        """Gradient (T, 2n) and Hessian (T, 2n, 2n) of r(x, a, x′) in z = (x, x′) at each step, by central
        differences of model.reward on rows (every pair of entries at once): r(z ± h_i e_i ± h_j e_j) for i ≤ j, which
        on the diagonal are z ± 2h_i e_i and z. Zero on flags and counters, and after the row has ended."""
        T, n = X.shape
        idx = np.flatnonzero(np.concatenate([self.real, self.real]))
        Z = np.concatenate([X, X_next], axis=1)
        h = self.FD_STEP * np.maximum(1.0, np.abs(Z[:, idx]))  # (T, k)
        I, J = np.triu_indices(len(idx))
        signs = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]])
        points = np.repeat(Z[:, None, None], len(I), axis=1).repeat(4, axis=2)  # (T, pairs, 4, 2n)
        pair, sign = np.arange(len(I))[:, None], np.arange(4)[None]
        points[:, pair, sign, idx[I][:, None]] += signs[:, 0] * h[:, I][..., None]
        points[:, pair, sign, idx[J][:, None]] += signs[:, 1] * h[:, J][..., None]
        flat = points.reshape(-1, 2 * n)
        r = self.model.reward(flat[:, :n], np.repeat(U, 4 * len(I), axis=0), flat[:, n:]).reshape(T, len(I), 4)
        second = (r[..., 0] - r[..., 1] - r[..., 2] + r[..., 3]) / (4 * h[:, I] * h[:, J])
        diagonal = I == J
        second[:, diagonal] = (r[:, diagonal, 0] - 2 * r[:, diagonal, 1] + r[:, diagonal, 3]) / (4 * h**2)
        gradient, hessian = np.zeros((T, 2 * n)), np.zeros((T, 2 * n, 2 * n))
        gradient[:, idx] = (r[:, diagonal, 0] - r[:, diagonal, 3]) / (4 * h)
        hessian[:, idx[I], idx[J]] = second
        hessian[:, idx[J], idx[I]] = second
        # a difference that leaves the reward's domain (a stored lift moved below its floor of 1e-4) is no slope: 0
        gradient, hessian = (np.nan_to_num(d, nan=0.0, posinf=0.0, neginf=0.0) for d in (gradient, hessian))
        return gradient * alive[:, None], hessian * alive[:, None, None]

    def backward(self, A, B, gradient, hessian):
        """Feedforward k (T, m) and feedback K (T, m, n) maximizing the quadratic model of the return, or None when
        Q_uu − μI is not negative definite (the return must curve down in the action for a maximum)."""
        T, n, m = B.shape
        V_x, V_xx = np.zeros(n), np.zeros((n, n))
        ks, Ks = np.zeros((T, m)), np.zeros((T, m, n))
        for t in reversed(range(T)):
            r_ab, r_bb = hessian[t, :n, n:], hessian[t, n:, n:]
            g, G = gradient[t, n:] + V_x, r_bb + V_xx  # the next state's value, this step's reward of it included
            Q_x = gradient[t, :n] + A[t].T @ g
            Q_u = B[t].T @ g
            Q_xx = hessian[t, :n, :n] + r_ab @ A[t] + A[t].T @ r_ab.T + A[t].T @ G @ A[t]
            Q_ux = B[t].T @ (r_ab.T + G @ A[t])
            Q_uu = B[t].T @ G @ B[t] - self.mu * np.eye(m)
            try:
                L = np.linalg.cholesky(-Q_uu)
            except np.linalg.LinAlgError:
                return None
            ks[t] = scipy.linalg.cho_solve((L, True), Q_u)
            Ks[t] = scipy.linalg.cho_solve((L, True), Q_ux)
            V_x = Q_x + Ks[t].T @ Q_uu @ ks[t] + Ks[t].T @ Q_u + Q_ux.T @ ks[t]
            V_xx = Q_xx + Ks[t].T @ Q_uu @ Ks[t] + Ks[t].T @ Q_ux + Q_ux.T @ Ks[t]
            V_xx = (V_xx + V_xx.T) / 2
        return ks, Ks

    def forward(self, x, X, U, ks, Ks):
        """(returns, plans) of the closed loop u = ū + α k + K (x̂ − x̄), one row per step size α, rolled out
        together."""
        alphas = self.ALPHAS[:, None]

        def act(t, Xh):
            return np.clip(U[t] + alphas * ks[t] + (Xh - X[t]) @ Ks[t].T, self.low, self.high)

        returns, _, trials, _ = rollout(self.model, np.repeat(x[None], len(self.ALPHAS), axis=0), act, self.steps)
        return returns, trials


PLANNER_CLASSES = {"mpc": MPPI, "ilqr": ILQR}


def planner(name: str, env_id: str, seed: int = 0, **overrides) -> Planner:
    """A planner by its name in agents.evaluate ("mpc": MPPI, "ilqr"), seeded."""
    if name not in PLANNER_CLASSES:
        raise ValueError(f"planner {name!r} is not one of {list(PLANNER_CLASSES)}")
    return PLANNER_CLASSES[name](env_id, seed, **overrides)


def check_planner(env_id: str, name: str):
    """ValueError, in one line, where the planner cannot run on the env: its model does not step, reward, terminate
    or (iLQR) differentiate rows at a reset state."""
    try:
        env = gym.make(env_id, **registry[env_id].make_kwargs()).unwrapped
        env.reset(seed=0)
        model = env.model
        x = np.stack([model.pack(env.state)] * 2)
        a = np.full((2, model.m), 0.3)
        X = model.step(x, a)
        model.reward(x, a, X), model.terminated(X)
        if name == "ilqr":
            model.jacobians(x, a)
    except Exception as error:  # whatever the model raises: the planner cannot run, and the reason is named
        reason = f"{type(error).__name__}: {error}" if not isinstance(error, ValueError) else str(error)
        raise ValueError(cli.one_line(f"planner {name!r} cannot run on {env_id}: {reason}")[:300]) from error
