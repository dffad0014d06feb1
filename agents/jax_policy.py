"""A policy trained on connenv.jax (agents.jax_ppo), as a file that numpy alone runs.

A policy file (``policy.npz``, ``best_policy.npz`` in a run folder of ``python train.py --backend jax``) holds the
actor's layers (``pi_W0``, ``pi_b0``, …), the critic's (``vf_…``), the Gaussian's ``log_std``, the observation
statistics it was trained with (``obs_mean``, ``obs_var``) and ``meta``, a JSON text: the env id, the observation
keys (a goal env's Dict observation is its keys' arrays concatenated in sorted order, as SB3's MultiInputPolicy
does), the clip of normalized observations and the action bounds. `forward` is written once on an array namespace
(numpy here, jax.numpy in training), so that the numbers the evaluation runs are the ones that were trained.

``python -m agents.evaluate --policy jax:PATH`` runs one (PATH a policy file, or a run folder: its best_policy.npz)
on the numpy env, deterministically: the Gaussian's mean, clipped to the action bounds.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

OBS_EPSILON = 1e-8  # VecNormalize's: added to the variance before its square root


def flat_observation(obs, keys: list[str] | None, xp=np):
    """An observation as one array (…, d): a Dict observation's entries at `keys` concatenated (sorted by SB3)."""
    if keys is None:
        return xp.asarray(obs)
    return xp.concatenate([xp.asarray(obs[key]) for key in keys], axis=-1)


def normalize(obs, mean, var, clip: float, xp=np):
    """VecNormalize's observation normalization: (obs − mean) / √(var + ε), clipped to ±clip."""
    return xp.clip((obs - mean) / xp.sqrt(var + OBS_EPSILON), -clip, clip)


def forward(layers, x, xp=np):
    """A tanh MLP: each hidden layer tanh(x W + b), the last linear. layers: [(W, b), …]."""
    for i, (W, b) in enumerate(layers):
        x = x @ W + b
        if i < len(layers) - 1:
            x = xp.tanh(x)
    return x


def gru(cell: dict, h, x, xp=np):
    """A GRU cell (Cho et al. 2014) of hidden state h (…, H) and input x: gates r, z and the candidate n from
    x Wx + b and h Wh (their columns in that order), h′ = (1 − z) n + z h. cell: {"Wx", "Wh", "b"}."""
    H = h.shape[-1]
    gx, gh = x @ cell["Wx"] + cell["b"], h @ cell["Wh"]
    r = 1.0 / (1.0 + xp.exp(-(gx[..., :H] + gh[..., :H])))
    z = 1.0 / (1.0 + xp.exp(-(gx[..., H : 2 * H] + gh[..., H : 2 * H])))
    n = xp.tanh(gx[..., 2 * H :] + r * gh[..., 2 * H :])
    return (1.0 - z) * n + z * h


def features(cell: dict | None, h, x, xp=np):
    """(h′, the heads' input): without a cell (an MLP policy) (h, x); with one, the GRU's next state from the
    normalized observation x, and x with it appended, which the policy's and the value's MLPs read."""
    if cell is None:
        return h, x
    h = gru(cell, h, x, xp)
    return h, xp.concatenate([x, h.astype(x.dtype)], axis=-1)


def save(path: str | Path, params: dict, obs_mean, obs_var, meta: dict):
    """Write a policy file (params: {"pi": [(W, b), …], "vf": […], "log_std": array}) atomically."""
    arrays = {"log_std": np.asarray(params["log_std"]), "obs_mean": np.asarray(obs_mean),
              "obs_var": np.asarray(obs_var), "meta": np.array(json.dumps(meta))}  # fmt: skip
    for net in ("pi", "vf"):
        for i, (W, b) in enumerate(params[net]):
            arrays[f"{net}_W{i}"], arrays[f"{net}_b{i}"] = np.asarray(W), np.asarray(b)
    for name, value in (params.get("gru") or {}).items():  # a recurrent policy's cell
        arrays[f"gru_{name}"] = np.asarray(value)
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, **arrays)
    tmp.replace(path)


def layers_of(data, net: str) -> list[tuple[np.ndarray, np.ndarray]]:
    count = sum(1 for key in data.files if key.startswith(f"{net}_W"))
    return [(data[f"{net}_W{i}"], data[f"{net}_b{i}"]) for i in range(count)]


class JaxPolicy:
    """A policy file run on numpy observations, with SB3's ``predict`` (deterministic: the mean, clipped)."""

    def __init__(self, path: str | Path, env_id: str | None = None):
        path = Path(path)
        if path.is_dir():
            path = path / "best_policy.npz"
        if not path.is_file():
            raise FileNotFoundError(f"policy 'jax:{path}': no such file; give a policy .npz or a run folder of "
                                    "train.py --backend jax")  # fmt: skip
        try:
            with np.load(path) as data:
                self.meta = json.loads(str(data["meta"]))
                self.pi, self.vf = layers_of(data, "pi"), layers_of(data, "vf")
                self.log_std, self.obs_mean, self.obs_var = data["log_std"], data["obs_mean"], data["obs_var"]
                self.cell = {k: data[f"gru_{k}"] for k in ("Wx", "Wh", "b")} if "gru_Wx" in data.files else None
        except (OSError, KeyError, ValueError) as error:
            raise ValueError(f"policy 'jax:{path}' is no policy file of train.py --backend jax ({error})") from error
        if env_id is not None and self.meta["env"] != env_id:
            raise ValueError(f"policy 'jax:{path}' was trained on {self.meta['env']}, not {env_id}")
        self.path = path
        self.low, self.high = np.asarray(self.meta["action_low"]), np.asarray(self.meta["action_high"])

    def action(self, obs, hidden=None) -> np.ndarray:
        """The deterministic action of an observation (or of rows of them); a recurrent policy's from its hidden
        state before the observation (zeros: an episode's start), which `step` returns with the action."""
        return self.step(obs, hidden)[0]

    def step(self, obs, hidden=None) -> tuple[np.ndarray, np.ndarray | None]:
        """(action, hidden state after the observation: None for an MLP policy)."""
        x = normalize(flat_observation(obs, self.meta["obs_keys"]), self.obs_mean, self.obs_var, self.meta["clip_obs"])
        if self.cell is not None and hidden is None:
            hidden = np.zeros((*x.shape[:-1], self.cell["Wh"].shape[0]))
        hidden, x = features(self.cell, hidden, x)
        return np.clip(forward(self.pi, x), self.low, self.high), hidden

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        """SB3's predict: a recurrent policy's state restarts where episode_start (as RecurrentPPO's)."""
        if self.cell is not None and state is not None and episode_start is not None:
            state = np.where(np.reshape(episode_start, (-1, *[1] * (np.ndim(state) - 1))), 0.0, state)
        action, state = self.step(obs, state)
        return action.astype(np.float32), state
