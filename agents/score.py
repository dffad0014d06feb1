"""The benchmark's score: each run's return normalized between random and the analytic controller, aggregated
over envs and seeds as rliable reports it (Agarwal et al., "Deep RL at the edge of the statistical precipice",
NeurIPS 2021).

    python -m agents.baselines score    # docs/baselines/score.md and its plots, from docs/baselines/unseen.json

A run's normalized score is (R − R_random) / (R_analytic − R_random), its mean return R and the references' on the
same episodes, reset with seeds no training, periodic evaluation, tuning or seed selection used (unseen.json says
which). 0 is random, 1 the analytic controller. The aggregates are rliable's: the interquartile mean (IQM, the mean
of the middle half of all runs' scores, robust to a few outliers yet using half of the runs, unlike a median), the
optimality gap (the mean shortfall below 1, so that a run beyond the controller does not hide another below
it), the performance profile (the fraction of runs above each score τ, averaged over envs) and the probability of
improvement P(X > Y) of one algorithm's run over another's on the same env, averaged over envs. Their 95% intervals
come from a stratified bootstrap: each env's runs resampled on their own, so that every resample keeps every env.

rliable itself is not used: its bootstrap comes from `arch`, whose releases (7.1, 7.2) fail to import beside
pandas 3. The same statistics are a few lines over scipy.stats.bootstrap, whose independent resampling of several
samples (paired=False) is the stratified bootstrap, one sample per env; its percentile intervals are rliable's.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy import stats

CONFIDENCE = 0.95
RESAMPLES = 20_000
BOOTSTRAP_SEED = 0  # the intervals are part of the docs, so they are reproducible
PROFILE_TAUS = np.linspace(0.0, 1.25, 51)


def normalized(returns: np.ndarray, random: float, analytic: float) -> float:
    """(R − R_random) / (R_analytic − R_random) of a run's mean return R."""
    return float((np.mean(returns) - random) / (analytic - random))


def iqm(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Interquartile mean: the mean of the scores between the 25th and the 75th percentile."""
    return stats.trim_mean(x, 0.25, axis=axis)


def optimality_gap(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Mean shortfall below the analytic controller's score 1; a score above 1 counts as 1."""
    return np.mean(np.maximum(1.0 - x, 0.0), axis=axis)


def pooled(statistic):
    """A statistic of all runs of all envs, as the bootstrap's function of one sample per env."""
    return lambda *envs, axis=-1: statistic(np.concatenate(envs, axis=axis), axis=axis)


def profile(*envs: np.ndarray, axis: int = -1) -> np.ndarray:
    """Performance profile: for each τ of PROFILE_TAUS, the fraction of an env's runs scoring above τ, averaged
    over envs (each env weighs the same whatever its number of seeds). τ is the first axis, as the bootstrap
    wants the resamples' axis last."""
    fractions = np.mean([np.mean(env[..., None] > PROFILE_TAUS, axis=axis - 1) for env in envs], axis=0)
    return np.moveaxis(fractions, -1, 0)


def improvement(*envs: np.ndarray, axis: int = -1) -> np.ndarray:
    """P(X > Y), ties counting half, of a run X of one algorithm over a run Y of the other on the same env,
    averaged over envs: the samples are X₁, …, X_k, Y₁, …, Y_k."""
    k = len(envs) // 2
    wins = []
    for x, y in zip(envs[:k], envs[k:], strict=True):
        x, y = x[..., :, None], y[..., None, :]
        wins.append(np.mean((x > y) + 0.5 * (x == y), axis=(-2, -1)))
    return np.mean(wins, axis=0)


def interval(statistic, samples: list[np.ndarray]) -> tuple:
    """(point, low, high): the statistic and its stratified-bootstrap 95% percentile interval. A statistic of
    identical resamples (every run the same) has the point as its interval."""
    samples = [np.asarray(sample, float) for sample in samples]
    point = statistic(*samples)
    if all(len(sample) < 2 or np.ptp(sample) == 0 for sample in samples):
        return point, point, point
    result = stats.bootstrap(
        samples,
        statistic,
        n_resamples=RESAMPLES,
        confidence_level=CONFIDENCE,
        method="percentile",
        paired=False,
        vectorized=True,
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    )
    return point, result.confidence_interval.low, result.confidence_interval.high


def mean_interval(values) -> tuple:
    """The mean over seeds with its 95% bootstrap interval (percentile; with few seeds it is about their range)."""
    return interval(lambda x, axis=-1: np.mean(x, axis=axis), [np.asarray(values, float)])


def aggregates(scores: dict[str, list[float]]) -> dict:
    """IQM and optimality gap of the normalized scores {env: [one per run]}, with their intervals."""
    envs = [np.asarray(runs, float) for runs in scores.values()]
    return {"iqm": interval(pooled(iqm), envs), "optimality_gap": interval(pooled(optimality_gap), envs)}


LABELS = {"ppo_jax": "PPO (JAX)"}
UNSHIPPED = ("ppo_jax",)  # algorithms whose runs are scored but of which no pretrained model ships  # train.py --backend jax's PPO (agents.jax_ppo); the others: their names in capitals


def algo_label(algo: str) -> str:
    return LABELS.get(algo, algo.upper())


def env_scores(entry: dict, key: str = "runs") -> dict[str, list[dict]]:
    """{algo: [run]} of an unseen.json env entry's runs (or another key's), each run with its mean return,
    success rate and normalized score."""
    random, analytic = np.mean(entry["random"]["returns"]), np.mean(entry["analytic"]["returns"])
    by_algo = {}
    for run in entry.get(key, []):
        by_algo.setdefault(run["algo"], []).append(
            {
                **run,
                "return": float(np.mean(run["returns"])),
                "success": float(np.mean(run["successes"])),
                "score": normalized(run["returns"], random, analytic),
            }
        )
    return by_algo


def cell(point, low, high, percent: bool = False) -> str:
    """'point [low, high]', as percentages with `percent`."""
    if percent:
        return f"{100 * point:.0f}% [{100 * low:.0f}%, {100 * high:.0f}%]"
    return f"{point:.4g} [{low:.4g}, {high:.4g}]"


def env_table(data: dict) -> list[str]:
    """Per env and algorithm, over all seeds: success, return and normalized score with their intervals, and the
    references'."""
    lines = [
        "| env | policy | seeds | success | return | normalized score | shipped model (seed): success, score |",
        "|---|---|---|---|---|---|---|",
    ]
    for env_id, entry in data["envs"].items():
        name = env_id.split("/")[-1]
        for label, ref in (("random", entry["random"]), (f"{entry['analytic']['name']} (analytic)", entry["analytic"])):
            success, ret = np.mean(ref["successes"]), np.mean(ref["returns"])
            score = 0 if label == "random" else 1
            lines.append(f"| {name} | {label} | – | {100 * success:.0f}% | {ret:.4g} | {score} | |")
            name = ""
        for algo, runs in env_scores(entry).items():
            cells = [mean_interval([run[key] for run in runs]) for key in ("success", "return", "score")]
            shipped = [f"{run['seed']}: {100 * run['success']:.0f}%, {run['score']:.3g}" for run in runs if run.get("shipped")]
            if algo in UNSHIPPED:
                shipped = ["none shipped"]
            lines.append(
                f"| | {algo_label(algo)} | {', '.join(str(run['seed']) for run in runs)} | {cell(*cells[0], percent=True)} "
                f"| {cell(*cells[1])} | {cell(*cells[2])} | {shipped[0] if shipped else 'an earlier round (below)'} |"
            )
    return lines


def latest(env_ids) -> list[str]:
    """The env ids without those of which a later version is among them (a task counts once in an aggregate)."""
    newest = {}
    for env_id in env_ids:
        name = env_id.rpartition("-v")[0]
        newest[name] = max(newest.get(name, env_id), env_id, key=lambda e: int(e.rpartition("-v")[2]))
    return [env_id for env_id in env_ids if newest[env_id.rpartition("-v")[0]] == env_id]


def release_table(data: dict) -> list[str]:
    """Per env, the earlier releases' shipped models (each the best of its seeds) on the same unseen episodes."""
    lines = ["| env | release | algorithm | seed (of) | success | normalized score |", "|---|---|---|---|---|---|"]
    for env_id, entry in data["envs"].items():
        for key in sorted(k for k in entry if k.startswith("pretrained")):
            for algo, (run,) in env_scores(entry, key).items():
                lines.append(
                    f"| {env_id.split('/')[-1]} | {key.removeprefix('pretrained ')} | {algo_label(algo)} "
                    f"| {run['seed']} ({run['of_seeds']}) | {100 * run['success']:.0f}% | {run['score']:.3g} |"
                )
    return lines


def pooled_scores(data: dict, key: str = "runs", shipped: bool = False) -> dict[str, dict[str, list[float]]]:
    """{algo: {env: [normalized score per run]}} over the envs that have runs of the algorithm (with shipped, only
    the run whose model is shipped), each task in its latest version that has them."""
    scores = {}
    for env_id, entry in data["envs"].items():
        for algo, runs in env_scores(entry, key).items():
            scores.setdefault(algo, {})[env_id] = [run["score"] for run in runs if run.get("shipped") or not shipped]
    return {algo: {env_id: by_env[env_id] for env_id in latest(by_env)} for algo, by_env in scores.items()}


def sets(data: dict) -> dict[str, dict]:
    """The run sets of unseen.json: this round's runs (all seeds), the models it ships (the best seed of each, beside
    which an earlier release's stand), and each earlier release's shipped models."""
    keys = sorted({key for entry in data["envs"].values() for key in entry if key.startswith("pretrained")})
    shipped = {"shipped": pooled_scores(data, shipped=True)}
    return {"runs": pooled_scores(data)} | shipped | {key: pooled_scores(data, key) for key in keys}


def set_label(key: str) -> str:
    if key in ("runs", "shipped"):
        return {"runs": "all seeds", "shipped": "this round's shipped models (best seed each)"}[key]
    return f"{key.removeprefix('pretrained ')} shipped models (best seed each)"


def aggregate_table(run_sets: dict[str, dict]) -> tuple[list[str], dict]:
    """IQM and optimality gap per algorithm and run set, and the probability of improvement of PPO over SAC on the
    envs both have; the lines of markdown and the numbers."""
    lines = [
        "| runs | algorithm | envs | runs | IQM | optimality gap |",
        "|---|---|---|---|---|---|",
    ]
    numbers = {}
    for key, scores in run_sets.items():
        for algo, by_env in sorted(scores.items()):
            by_env = {env_id: runs for env_id, runs in by_env.items() if runs}  # shipped sets: none of an unshipped
            if not by_env:
                continue
            result = aggregates(by_env)
            numbers[(key, algo)] = result
            n_runs = sum(map(len, by_env.values()))
            if n_runs == len(by_env):  # one run per env: a stratified resample is the sample itself
                iqm_cell, gap_cell = (f"{result[m][0]:.3g} (one run per env: no interval)" for m in result)
            else:
                iqm_cell, gap_cell = cell(*result["iqm"]), cell(*result["optimality_gap"])
            lines.append(f"| {set_label(key)} | {algo_label(algo)} | {len(by_env)} | {n_runs} | {iqm_cell} | {gap_cell} |")
    ppo, sac = run_sets["runs"].get("ppo", {}), run_sets["runs"].get("sac", {})
    both = sorted(set(ppo) & set(sac))
    if both:
        numbers["improvement"] = interval(improvement, [ppo[e] for e in both] + [sac[e] for e in both])
        lines += ["", f"P(PPO > SAC), all seeds, over the {len(both)} envs both have: {cell(*numbers['improvement'])}"]
    return lines, numbers


def plot_profiles(scores: dict[str, dict[str, list[float]]], path):
    """Performance profiles (fraction of runs above τ, averaged over envs) per algorithm, with 95% bands."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6))
    for algo, by_env in sorted(scores.items()):
        point, low, high = interval(profile, list(by_env.values()))
        (line,) = ax.plot(PROFILE_TAUS, point, label=f"{algo_label(algo)} ({len(by_env)} envs)")
        ax.fill_between(PROFILE_TAUS, low, high, color=line.get_color(), alpha=0.25)
    ax.axvline(1.0, ls="--", color="k", lw=1, label="analytic controller")
    ax.set(xlabel="normalized score τ", ylabel="fraction of runs with score > τ", ylim=(0, 1.02))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_aggregates(numbers: dict, path):
    """IQM and optimality gap of each (run set, algorithm), as points with their 95% intervals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pairs = [pair for pair in numbers if pair != "improvement"]
    fig, axes = plt.subplots(1, 2, figsize=(8, 0.5 + 0.45 * len(pairs)), sharey=True)
    for ax, metric, title in zip(axes, ("iqm", "optimality_gap"), ("IQM", "optimality gap"), strict=True):
        for i, pair in enumerate(pairs):
            point, low, high = numbers[pair][metric]
            ax.errorbar(point, i, xerr=[[point - low], [high - point]], fmt="o", capsize=3, color="k")
        ax.set(title=title, xlabel="normalized score")
    axes[0].set_yticks(range(len(pairs)), [f"{algo_label(algo)}, {set_label(key)}" for key, algo in pairs], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def missing(data: dict, envs, algos) -> list[str]:
    """The (env, algo) pairs of the benchmark without runs in unseen.json."""
    have = {(env_id, algo) for env_id, entry in data["envs"].items() for algo in env_scores(entry)}
    return [f"{env_id.split('/')[-1]} {algo_label(algo)}" for env_id in envs for algo in algos if (env_id, algo) not in have]


REFERENCE_KEYS = {"random": ("returns", "successes"), "analytic": ("name", "returns", "successes")}
RUN_KEYS = ("algo", "seed", "returns", "successes")  # and "of_seeds" in an earlier release's entry


def load(path) -> dict:
    """unseen.json's data, checked (`check`); a file that is no JSON is a ValueError naming it."""
    try:
        data = json.loads(Path(path).read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not JSON ({error})") from error
    return check(data, path)


def check(data, path) -> dict:
    """data, the contents of unseen.json at path, if it has every key `write` reads; else a ValueError naming the file
    and the first missing key (``envs["connenv/Swing-v0"]["random"]["returns"]``)."""

    def need(mapping, key, where):
        if not isinstance(mapping, dict) or key not in mapping:
            raise ValueError(f"{path}: no key {where}[{key!r}]" if where else f"{path}: no key {key!r}")
        return mapping[key]

    need(data, "first_seed", "")
    envs = need(data, "envs", "")
    if not isinstance(envs, dict) or not envs:
        raise ValueError(f"{path}: 'envs' holds no env")
    for env_id, entry in envs.items():
        where = f"envs[{env_id!r}]"
        for reference, keys in REFERENCE_KEYS.items():
            for key in keys:
                need(need(entry, reference, where), key, f"{where}[{reference!r}]")
            if not need(entry, reference, where)["returns"]:
                raise ValueError(f"{path}: {where}[{reference!r}]['returns'] is empty")
        for runs_key in [k for k in entry if k == "runs" or k.startswith("pretrained")]:
            for i, run in enumerate(entry[runs_key]):
                for key in RUN_KEYS + (("of_seeds",) if runs_key != "runs" else ()):
                    need(run, key, f"{where}[{runs_key!r}][{i}]")
    return data


def write(data: dict, docs, envs, algos) -> str:
    """docs/score.md, docs/score_profile.png and docs/score_aggregates.png from unseen.json's data; the markdown."""
    run_sets = sets(data)
    lines, numbers = aggregate_table(run_sets)
    first = data["first_seed"]
    episodes = len(next(iter(data["envs"].values()))["random"]["returns"])
    text = [
        "# Score",
        "",
        "Generated by `python -m agents.baselines score` from docs/baselines/unseen.json (agents/score.py says how).",
        f"Every policy ran the same {episodes} episodes per env, reset with seeds {first}–{first + episodes - 1},",
        "which no training, periodic evaluation, tuning, seed selection or table used. A run's normalized score is",
        "(R − R_random) / (R_analytic − R_random) of its mean return R on them; intervals are 95% bootstrap",
        "intervals, over the seeds for an env, stratified over envs for an aggregate.",
        "",
        "## Aggregate",
        "",
        *lines,
        "",
        "![performance profiles](score_profile.png)",
        "",
        "![aggregates](score_aggregates.png)",
        "",
        "## Per env, over all seeds",
        "",
        *env_table(data),
    ]
    text += ["", "## Earlier releases' shipped models", "", *release_table(data)]
    gaps = missing(data, envs, algos)
    if gaps:
        text += ["", f"Not yet trained with the current hyperparameters: {', '.join(gaps)}."]
    markdown = "\n".join(text) + "\n"
    (docs / "score.md").write_text(markdown)
    if run_sets["runs"]:
        plot_profiles(run_sets["runs"], docs / "score_profile.png")
    plot_aggregates(numbers, docs / "score_aggregates.png")
    return markdown
