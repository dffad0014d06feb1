"""Evaluate policies on the same seeded episodes and print one table row per policy.

    python -m agents.evaluate --env ID --policy analytic random runs/NAME_ppo_s0/connenv-NAME.zip

ID is a connenv id (``--help`` lists them), NAME the id without its namespace.

Episode i of every policy starts from ``reset(seed=seed + i)``, so the rows compare like with like. A policy is
``analytic`` (the env's first controller in agents.controllers), the name of one of its controllers (``arc``,
``holonomy``, ...), ``random`` (uniform actions, seeded), ``mpc`` or ``ilqr`` (planners on the env's own model,
agents.mpc, seeded), the zip of a trained SB3 model, or ``pretrained``: the env's models committed under
agents/pretrained/, one per algorithm (``python -m agents.baselines``). Columns
beyond return, success, time and length are the env's own measures, the info keys named by its
``metadata["measures"]``, averaged over the episodes' final infos. The rl-zoo3 run folder around a zip, as
``train.py`` and ``python -m rl_zoo3.train`` write it, tells the algorithm (``{env}/args.yml``) and the observation
statistics of VecNormalize (``{env}/vecnormalize.pkl``; for a best_model.zip, ``{env}/best_vecnormalize.pkl`` if
train.py kept it).
"""

from __future__ import annotations

import argparse
import copy
import importlib
import json
import os
import re
import sys
import zipfile
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np
import yaml
from gymnasium.wrappers import RenderCollection

import connenv  # noqa: F401  (registers the envs)
from agents.controllers import CONTROLLERS, controller, controller_names
from agents.mpc import PLANNERS, check_planner, planner
from agents.progress import progress
from connenv import cli
from connenv.cli import positive_int, seed_int, writable_file

PROG = "python -m agents.evaluate"
PRETRAINED = Path(__file__).parent / "pretrained"
ENV_IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))
DEFAULT_ENV = "connenv/Swing-v0"  # --env of this command and of train.py when none is given (README's first example)
CONTROLLER_NAMES = sorted({name for env_id in CONTROLLERS for name in controller_names(env_id)})
GIF_SIZE = 200  # pixels
GIF_FRAME_STRIDE = 2  # keep one frame in two


@dataclass
class Episode:
    """One evaluation episode: its return, whether it reached the target, when (simulated s), how many steps,
    and the env's measures at its end."""

    ret: float
    success: bool
    time: float
    length: int
    measures: dict


@dataclass
class Trace:
    """What `agents.plots` draws of an episode: the model's packed state x after reset and after each step
    (``env.unwrapped.model.pack``, named by its ``state_names``), the actions and the infos (``info["state"]``
    among them)."""

    states: list = field(default_factory=list)
    actions: list = field(default_factory=list)
    infos: list = field(default_factory=list)

    def record(self, env: gym.Env, info: dict, action=None):
        self.states.append(env.unwrapped.model.pack(env.unwrapped.state))
        self.infos.append(info)
        if action is not None:
            self.actions.append(np.array(action, float))


class RandomPolicy:
    """Uniform actions from the action space, drawn from its own seeded generator."""

    def __init__(self, action_space: gym.Space, seed: int):
        self.action_space = copy.deepcopy(action_space)
        self.action_space.seed(seed)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return self.action_space.sample(), state


class NormalizedPolicy:
    """A trained model fed observations normalized with the VecNormalize statistics it was trained with."""

    def __init__(self, model, vec_normalize):
        self.model, self.vec_normalize = model, vec_normalize

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return self.model.predict(self.vec_normalize.normalize_obs(obs), state, episode_start, deterministic)


def policy_spec(text: str) -> str:
    """argparse type: a controller name, 'random', a planner, 'pretrained', an existing model zip that SB3 saved or
    jax:PATH (a policy file of train.py --backend jax, or its run folder)."""
    if text in (*CONTROLLER_NAMES, "random", *PLANNERS, "pretrained"):
        return text
    if text.startswith("jax:"):
        from agents.jax_policy import JaxPolicy

        try:
            JaxPolicy(text.removeprefix("jax:"))
        except (OSError, ValueError) as error:
            raise argparse.ArgumentTypeError(str(error)) from error
        return text
    if not (text.endswith(".zip") and Path(text).is_file()):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not one of {CONTROLLER_NAMES}, 'random', {', '.join(map(repr, PLANNERS))}, 'pretrained' or "
            "an existing PATH.zip"
        )
    try:
        check_model_zip(Path(text))
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from error
    return text


def check_policy(env_id: str, spec: str):
    """ValueError if spec names a controller the env lacks, a planner that cannot run on it, or 'pretrained' for an env
    without pretrained models: checked before any policy runs its episodes."""
    if spec in PLANNERS:
        check_planner(env_id, spec)
    names = controller_names(env_id) if env_id in CONTROLLERS else []
    if spec in CONTROLLER_NAMES and spec not in names:
        raise ValueError(f"{spec!r} is no controller of {env_id}; its controllers: {names or 'none'}")
    if spec == "pretrained":
        pretrained_models(env_id)


def png_file(text: str) -> str:
    """argparse type: a writable path ending in .png (agents.plots writes PNGs only)."""
    if Path(text).suffix.lower() != ".png":
        raise argparse.ArgumentTypeError(f"{text!r} does not end in .png (the figure is a PNG)")
    return writable_file(text)


def gif_file(text: str) -> str:
    """argparse type: a writable path ending in .gif (save_gif writes GIFs only)."""
    if Path(text).suffix.lower() != ".gif":
        raise argparse.ArgumentTypeError(f"{text!r} does not end in .gif (the video is a GIF)")
    return writable_file(text)


def check_model_zip(path: Path):
    """ValueError unless path is a zip whose members are intact (their CRCs) and hold SB3's "data" (the model's
    parameters as JSON), so that an empty, truncated or foreign file is named as such rather than by SB3's loader."""
    try:
        with zipfile.ZipFile(path) as archive:
            broken, names = archive.testzip(), archive.namelist()
    except (zipfile.BadZipFile, EOFError) as error:
        raise ValueError(f"{str(path)!r} is not a zip file ({error}); give a model zip that SB3 saved") from error
    if broken is not None:
        raise ValueError(f"{str(path)!r} is corrupt: its member {broken!r} fails its CRC check")
    if "data" not in names:
        raise ValueError(f"{str(path)!r} is a zip, but no SB3 model: it holds no 'data' member")


def pretrained_models(env_id: str) -> list[Path]:
    """The env's models under agents/pretrained/ ({env}_{algo}/best_model.zip), by algorithm."""
    models = sorted(PRETRAINED.glob(f"{env_id.split('/')[-1]}_*/best_model.zip"))
    if not models:
        raise ValueError(f"policy 'pretrained': no model for {env_id} under {PRETRAINED}")
    return models


def run_file(model_path: Path, name: str) -> Path | None:
    """A file of the rl-zoo3 run folder around a model zip ({run}/{env}/name), or None."""
    return next(model_path.parent.glob(f"*/{name}"), None)


def algo_of(model_path: Path) -> str:
    """The algorithm that trained a model zip, read from its run folder's args.yml."""
    args_file = run_file(model_path, "args.yml")
    if args_file is None:
        raise ValueError(f"cannot tell which algorithm trained {model_path}: no run folder args.yml; pass --algo")
    return yaml.load(args_file.read_text(), Loader=yaml.UnsafeLoader)["algo"]  # rl-zoo3 writes an OrderedDict


def env_kwargs_of(specs: str | list[str] | None) -> dict:
    """The make kwargs of --env-kwargs: each spec a JSON object (``'{"dt": 0.02}'``) or ``module:factory``, a
    function of a module in the working directory or on the Python path that returns the kwargs dict or a system,
    which becomes {"system": system} (ActiveConstraintEnv's); a later spec updates the earlier ones, so that
    ``my_robot:system '{"u_low": -3, "u_high": 3}'`` completes a system with its bounds. None: no kwargs. A spec
    that gives no kwargs raises ValueError naming it."""
    kwargs = {}
    for spec in [specs] if isinstance(specs, str) else specs or []:
        kwargs.update(json_kwargs(spec) if spec.lstrip().startswith("{") else factory_kwargs(spec))
    return kwargs


def json_kwargs(spec: str) -> dict:
    try:
        return json.loads(spec)
    except json.JSONDecodeError as error:
        raise ValueError(f"--env-kwargs {spec!r} is not a JSON object ({error})") from error


def factory_kwargs(spec: str) -> dict:
    """factory()'s kwargs (a system alone as {"system": system}) of module:factory, the module imported from the
    working directory first, where `python train.py` (whose path starts at its own folder) would not look."""
    module_name, _, name = spec.partition(":")
    if not module_name or not name:
        raise ValueError(f"--env-kwargs {spec!r} is neither a JSON object ('{{\"dt\": 0.02}}') nor module:factory")
    here = os.getcwd()
    sys.path.insert(0, here)
    try:
        made = getattr(importlib.import_module(module_name), name)()
    except Exception as error:  # the user's module or factory: name the spec and the error it raised
        raise ValueError(f"--env-kwargs {spec!r}: {type(error).__name__}: {error}") from error
    finally:
        sys.path.remove(here)
    return dict(made) if isinstance(made, Mapping) else {"system": made}


def make_kwargs(env_id: str, specs: str | list[str] | None) -> dict:
    """env_kwargs_of(specs), checked by making the env once: kwargs it refuses (or missing ones it needs) end the
    command before its work, in a ValueError naming --env-kwargs."""
    kwargs = env_kwargs_of(specs)
    try:
        gym.make(env_id, **kwargs).close()
    except (ValueError, TypeError) as error:
        given = " ".join([specs] if isinstance(specs, str) else specs or ["(none)"])
        raise ValueError(f"{env_id} refuses --env-kwargs {given}: {error}") from error
    return kwargs


def load_model(model_path: str | Path, env_id: str, algo: str | None = None, env_kwargs: dict | None = None):
    """An SB3 model checked against the env's spaces, behind its VecNormalize statistics if it has some."""
    from rl_zoo3.utils import ALGOS
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    model_path = Path(model_path)
    if not model_path.is_file():
        raise FileNotFoundError(f"policy {str(model_path)!r}: no such file; give 'analytic', 'random' or a model zip")
    check_model_zip(model_path)
    algo = algo or algo_of(model_path)
    if algo not in ALGOS:
        raise ValueError(f"algo {algo!r} is not one of {sorted(ALGOS)}")
    env = gym.make(env_id, **(env_kwargs or {}))
    goal_env = isinstance(env.observation_space, gym.spaces.Dict)  # SB3 loads a HER model only with its env
    try:
        model = ALGOS[algo].load(model_path, device="cpu", **({"env": DummyVecEnv([lambda: env])} if goal_env else {}))
    except (AssertionError, AttributeError, KeyError, TypeError, ValueError) as error:  # SB3's, of a file not algo's
        raise ValueError(
            f"{model_path}: SB3's {algo.upper()} cannot load it ({type(error).__name__}: {error}); "
            "was it trained with another algorithm (--algo)?"
        ) from error
    for space in ("observation_space", "action_space"):
        if getattr(model, space) != getattr(env, space):
            raise ValueError(
                f"{model_path} was trained with {space} {getattr(model, space)}, but {env_id} has {getattr(env, space)}"
            )
    stats = run_file(model_path, "best_vecnormalize.pkl") if model_path.stem == "best_model" else None
    stats = stats or run_file(model_path, "vecnormalize.pkl")
    if stats is None:
        return model
    vec_normalize = VecNormalize.load(str(stats), DummyVecEnv([lambda: env]))
    vec_normalize.training = False
    return NormalizedPolicy(model, vec_normalize)


def make_policy(
    spec: str, env_id: str, seed: int, algo: str | None = None, env_kwargs: dict | None = None
) -> tuple[str, object]:
    """(label, policy) for a controller name, 'random', a planner or a model zip; a zip's label is algo:run-folder."""
    if spec in PLANNERS:
        return spec, planner(spec, env_id, seed)
    if spec in CONTROLLER_NAMES:
        return spec, controller(env_id, spec)
    if spec == "random":
        return spec, RandomPolicy(gym.make(env_id, **(env_kwargs or {})).action_space, seed)
    if spec.startswith("jax:"):
        from agents.jax_policy import JaxPolicy

        policy = JaxPolicy(spec.removeprefix("jax:"), env_id)
        return jax_label(policy.path), policy
    if not spec.endswith(".zip"):
        raise ValueError(
            f"policy {spec!r} is not one of {controller_names(env_id)}, 'random', 'pretrained', a model PATH.zip or "
            "jax:PATH"
        )
    algo = algo or algo_of(Path(spec))
    return f"{algo}:{Path(spec).parent.name}", load_model(spec, env_id, algo, env_kwargs)


def jax_label(path: str | Path) -> str:
    """The label of a policy file of connenv.jax's trainers: {algo}:{its run folder}, the algo read from the folder's
    name {env}_{algo}_s{seed} (ppo_jax of train.py --backend jax, shac_jax and apg_jax of agents.jax_shac)."""
    path = Path(path)
    folder = (path.parent if path.suffix == ".npz" else path).name
    algo = re.search(r"_((?:shac|apg)_jax)_s\d+$", folder)
    return f"{algo.group(1) if algo else 'ppo_jax'}:{folder}"


def run_episode(env: gym.Env, policy, seed: int, trace: Trace | None = None) -> Episode:
    """One episode from reset(seed=seed), deterministic actions; a planner (a policy with ``bind``) is bound to env
    first, since it plans from the env's state. ``trace``: a Trace that records it (the others skip the packing)."""
    if hasattr(policy, "bind"):
        policy.bind(env)
    obs, info = env.reset(seed=seed)
    if trace is not None:
        trace.record(env, info)
    ret, length, done, state = 0.0, 0, False, None
    while not done:  # state and episode_start as SB3's evaluate_policy passes them, for recurrent policies
        action, state = policy.predict(obs, state=state, episode_start=np.array([length == 0]), deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        if trace is not None:
            trace.record(env, info, action)
        ret, length, done = ret + float(reward), length + 1, terminated or truncated
    measures = {key: float(info[key]) for key in env.unwrapped.metadata.get("measures", ())}
    return Episode(ret, bool(info["is_success"]), float(info["state"]["t"]), length, measures)


def save_gif(frames: list[np.ndarray], path: str | Path, fps: float):
    """A small looping GIF: every GIF_FRAME_STRIDE-th frame, GIF_SIZE pixels wide."""
    from PIL import Image

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(frame) for frame in frames[::GIF_FRAME_STRIDE]]
    images = [image.resize((GIF_SIZE, GIF_SIZE * image.height // image.width)) for image in images]
    duration = round(1000 * GIF_FRAME_STRIDE / fps)
    images[0].save(path, save_all=True, append_images=images[1:], duration=duration, loop=0)


def evaluate(
    env_id: str,
    policy,
    episodes: int,
    seed: int,
    video: str | Path | None = None,
    env_kwargs: dict | None = None,
    trace: Trace | None = None,
    desc: str | None = None,
) -> list[Episode]:
    """Episodes reset with seeds seed, seed + 1, ...; with `video`, the first is also written as a GIF; with
    `trace`, the first is recorded in it; with `desc`, their progress is shown on stderr under that name."""
    env_kwargs = env_kwargs or {}
    env = gym.make(env_id, **env_kwargs)
    first_env = RenderCollection(gym.make(env_id, render_mode="rgb_array", **env_kwargs)) if video else env
    indices = range(episodes) if desc is None else progress(range(episodes), episodes, "episodes", desc)
    results = [run_episode(first_env if i == 0 else env, policy, seed + i, trace if i == 0 else None) for i in indices]
    if video:
        save_gif(first_env.render(), video, env.metadata["render_fps"])
    env.close()
    first_env.close()
    return results


def summarize(label: str, episodes: list[Episode]) -> dict:
    """Mean ± std return, success rate, mean time to success (over successes, None if none), mean length, and the
    mean of each of the env's measures."""
    returns = np.array([e.ret for e in episodes])
    times = [e.time for e in episodes if e.success]
    measures = {key: float(np.mean([e.measures[key] for e in episodes])) for key in episodes[0].measures}
    return {
        "policy": label,
        "return_mean": float(returns.mean()),
        "return_std": float(returns.std()),
        "success_rate": float(np.mean([e.success for e in episodes])),
        "time_to_success_mean": float(np.mean(times)) if times else None,
        "length_mean": float(np.mean([e.length for e in episodes])),
        "measures_mean": measures,
        "episodes": [asdict(e) for e in episodes],
    }


def expand_pretrained(specs: list[str], env_id: str, algo: str | None) -> list[tuple[str, str | None]]:
    """(spec, algo) pairs, 'pretrained' replaced by the env's pretrained zips with their own algorithms."""
    pairs = []
    for spec in specs:
        pairs += [(str(model), None) for model in pretrained_models(env_id)] if spec == "pretrained" else [(spec, algo)]
    return pairs


def compare(
    env_id: str,
    specs: list[str],
    episodes: int = 100,
    seed: int = 0,
    algo: str | None = None,
    video=None,
    env_kwargs: dict | None = None,
    plot=None,
) -> dict:
    """Evaluate each policy spec on the same episodes; `video` films the first policy's first episode, `plot` draws
    every policy's first episode (agents.plots). `algo` applies to the zips given by path; a pretrained model's is
    read from its folder. env_kwargs: gym.make's."""
    rows, traces = [], {}
    for i, (spec, spec_algo) in enumerate(expand_pretrained(specs, env_id, algo)):
        label, policy = make_policy(spec, env_id, seed, spec_algo, env_kwargs)
        trace = Trace() if plot else None
        if plot:  # a policy given twice is drawn twice
            traces[f"{label} ({i + 1})" if label in traces else label] = trace
        episodes_run = evaluate(env_id, policy, episodes, seed, video if i == 0 else None, env_kwargs, trace, label)
        rows.append(summarize(label, episodes_run))
    if plot:
        from agents.plots import draw

        draw(env_id, traces, plot, env_kwargs, seed, episodes)
    return {"env": env_id, "seed": seed, "episodes": episodes, "policies": rows}


def format_table(report: dict) -> str:
    """The report as a text table, one row per policy."""
    width = max(len("policy"), *(len(row["policy"]) for row in report["policies"]))
    seeds = f"seeds {report['seed']}..{report['seed'] + report['episodes'] - 1}"
    measures = list(report["policies"][0]["measures_mean"])
    lines = [
        f"{report['env']}: {report['episodes']} episodes, {seeds}",
        f"{'policy':<{width}}  {'return':>15}  {'success':>7}  {'time to target (s)':>18}  {'length':>6}"
        + "".join(f"  {key:>12}" for key in measures),
    ]
    for row in report["policies"]:
        ret = f"{row['return_mean']:.3f} ± {row['return_std']:.3f}"
        time = "-" if row["time_to_success_mean"] is None else f"{row['time_to_success_mean']:.2f}"
        success = f"{100 * row['success_rate']:.0f}%"
        extra = "".join(f"  {row['measures_mean'][key]:>#12.4g}" for key in measures)
        lines.append(
            f"{row['policy']:<{width}}  {ret:>15}  {success:>7}  {time:>18}  {row['length_mean']:>6.1f}{extra}"
        )
    return "\n".join(lines)


def write_json(report: dict, path: str | Path):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=1))


ENV_KWARGS_HELP = (
    "the make kwargs of --env: a JSON object ('{\"dt\": 0.02}') or module:factory (a function of a module in the "
    "working directory returning the kwargs or a system); several update one another in order"
)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default=DEFAULT_ENV, choices=ENV_IDS, help="default: %(default)s")
    parser.add_argument(
        "--policy",
        nargs="+",
        type=policy_spec,
        default=["analytic", "random"],
        help=f"one of {CONTROLLER_NAMES} (the env's controllers; analytic is its first), random, mpc or ilqr"
        " (planners on the env's model, agents.mpc), pretrained (agents/pretrained/), PATH.zip (SB3) or jax:PATH (a"
        " policy of train.py --backend jax: its .npz or its run folder)",
    )
    parser.add_argument("--algo", help="algorithm of the zips (default: read from their run folder)")
    parser.add_argument("--episodes", type=positive_int, default=100)
    parser.add_argument("--seed", type=seed_int, default=0, help="episode i is reset with seed + i")
    parser.add_argument(
        "--json", type=writable_file, help="default: runs/eval_{env}_s{seed}.json, with --plot FILE.png FILE.json"
    )
    parser.add_argument("--video", type=gif_file, help="GIF of the first policy's first episode")
    parser.add_argument(
        "--plot",
        type=png_file,
        metavar="FILE.png",
        help="draw each policy's first episode (reset seed --seed) in one figure (agents.plots): for an env with a mechanical connection "
        "the shape path over the curvature map and the net motion beside its prediction, for an active-constraint "
        "env the phase portrait coloured by the control and the energy (or the env's measure) against time",
    )
    parser.add_argument("--env-kwargs", nargs="+", metavar="KWARGS", help=ENV_KWARGS_HELP)
    args = parser.parse_args(argv)
    for spec in args.policy:
        try:
            check_policy(args.env, spec)
        except ValueError as error:
            parser.error(f"argument --policy: {error}")
    if args.algo is not None:
        from rl_zoo3.utils import ALGOS

        if args.algo not in ALGOS:
            parser.error(f"argument --algo: invalid choice: {args.algo!r} (choose from {', '.join(sorted(ALGOS))})")
    if args.json is None:  # a figure's report beside it: the default file may hold the README's 100 episodes
        default = f"runs/eval_{args.env.split('/')[-1]}_s{args.seed}.json"
        args.json = str(Path(args.plot).with_suffix(".json")) if args.plot else default
        if reason := cli.unwritable(Path(args.json), directory=False):
            parser.error(f"argument --json: the default {args.json!r} {reason}")
    return args


def main(argv: list[str] | None = None) -> dict:
    args = parse_args(argv)
    env_kwargs = make_kwargs(args.env, args.env_kwargs)
    report = compare(args.env, args.policy, args.episodes, args.seed, args.algo, args.video, env_kwargs, args.plot)
    print(format_table(report))
    write_json(report, args.json)
    print(f"wrote {args.json}" + "".join(f" and {path}" for path in (args.video, args.plot) if path))
    return report


if __name__ == "__main__":
    cli.run(main, PROG)
