"""Exact gradients against PPO: SHAC (agents.jax_shac) beside PPO (train.py --backend jax) on five envs, and the
step Jacobian's spectrum along a trained policy's rollout; writes docs/guides/exact-gradients.md and its chart.

    python -m agents.exact_gradients            # 5 seeds each, the budgets of ENVS (each training < 8 min here)
    python -m agents.exact_gradients --quick    # 2 seeds, 3·10⁴ steps, two envs: the pipeline end to end

Each training is a subprocess (``python train.py --backend jax`` and ``python -m agents.jax_shac``) that writes its
run folders under --runs; a finished one (its results.json) is reused unless --retrain. Both evaluate their best
policies on the numpy env on the same unseen episodes (reset seeds 100000 …, agents.baselines.UNSEEN_SEED). Where
reverse mode does not run through an env's step yet, SHAC is not trained and the page says so (with the error).

The spectrum (Suh et al., ICML 2022): along a deterministic episode of a trained policy on the JAX env, the Jacobian
of the closed-loop step x_{t+1} = f(x_t, π(obs(x_t))) by ``jax.jacfwd`` — what backpropagation through a window
multiplies — its largest singular value per step, and the finite-time Lyapunov exponent of windows of h = 32 steps,
λ_h = (1/h) ln σ_max(J_{t+h−1} ⋯ J_t) per step: a gradient through such a window is scaled by up to e^{h λ_h}.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "guides" / "exact-gradients.md"
CHART = "exact-gradients.png"
UNSEEN = 100_000  # agents.baselines.UNSEEN_SEED
HORIZON = 32
TIMEOUT = 480  # seconds per training

# id: (steps per seed, numpy episodes per seed at the end, spectrum steps)
ENVS = {
    "connenv/Swing-v0": (2e5, 100, 500),
    "connenv/RollingBall-v0": (2e5, 100, 200),
    "connenv/TubeTwist-v0": (2e5, 100, 200),
    "connenv/RollingBallPose-v0": (3e5, 100, 300),
    "connenv/KapitzaSwingUp-v0": (2e5, 20, 2000),
}
QUICK = {"connenv/Swing-v0": (3e4, 10, 100), "connenv/RollingBall-v0": (3e4, 10, 100)}
ALGOS = ("ppo_jax", "shac_jax")
NAMES = {"ppo_jax": "PPO", "shac_jax": "SHAC"}


def short(env_id: str) -> str:
    return env_id.split("/")[-1]


def folders(runs: Path, env_id: str, algo: str, seeds: int) -> list[Path]:
    return [Path(runs) / f"{short(env_id)}_{algo}_s{s}" for s in range(seeds)]


# -- reverse mode -----------------------------------------------------------------------------------------------


def reverse_mode(env_id: str) -> str | None:
    """None where jax.grad runs through 3 steps of the env's rows; else the error's first line."""
    import jax
    import jax.numpy as jnp

    import connenv.jax

    env, params = connenv.jax.make(env_id)
    _, state = env.reset_rows(jax.random.key(0), 2, params)
    shape = env.action_space().shape

    def total(actions):
        s, out = state, 0.0
        for a in actions:
            _, s, r, *_ = env.step_env_rows(None, s, a, params)
            out = out + r.sum()
        return out

    try:
        gradient = jax.grad(total)(jnp.full((3, 2, *shape), 0.1))
        jax.block_until_ready(gradient)
    except Exception as error:  # noqa: BLE001  (JAX's transpose errors are TypeErrors, NotImplementedErrors, …)
        return f"{type(error).__name__}: {str(error).strip().splitlines()[0][:160]}"
    return None


# -- trainings ----------------------------------------------------------------------------------------------------


def train(env_id: str, algo: str, seeds: int, steps: float, episodes: int, runs: Path, retrain: bool) -> dict:
    """Run (or reuse) one algorithm's seeds on one env in a subprocess: {"status", "seconds", "log"}."""
    done = folders(runs, env_id, algo, seeds)
    if not retrain and all((f / "results.json").is_file() for f in done):
        return {"status": "reused"}
    common = ["--env", env_id, "--seeds", str(seeds), "--timesteps", str(int(steps)), "--runs", str(runs),
              "--eval-episodes", str(episodes), "--eval-seed", str(UNSEEN), "--overwrite"]  # fmt: skip
    if algo == "ppo_jax":
        command = [sys.executable, str(ROOT / "train.py"), "--backend", "jax", *common]
    else:
        command = [sys.executable, "-m", "agents.jax_shac", *common]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    start = time.perf_counter()
    print(f"  {' '.join(command[1:])}", flush=True)
    try:
        out = subprocess.run(command, check=False, cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"status": f"timed out after {TIMEOUT} s", "seconds": TIMEOUT}
    seconds = time.perf_counter() - start
    lines = [line for line in out.stdout.splitlines() if "episodes/s" not in line]
    print("\n".join("    " + line for line in lines[-12:]), flush=True)
    if out.returncode:
        return {"status": f"failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}",
                "seconds": seconds}  # fmt: skip
    return {"status": "trained", "seconds": seconds}


def curves(folder: Path) -> dict | None:
    """The periodic evaluations on the JAX env: timesteps, wall seconds, mean return and success."""
    if not (folder / "evaluations.npz").is_file():
        return None
    with np.load(folder / "evaluations.npz") as data:
        steps, returns, successes = data["timesteps"], data["results"].mean(1), data["successes"].mean(1)
    seconds = {}
    if (folder / "progress.csv").is_file():
        with open(folder / "progress.csv") as file:
            seconds = {int(float(r["timesteps"])): float(r["seconds"]) for r in csv.DictReader(file)}
    wall = np.array([seconds.get(int(s), np.nan) for s in steps])
    return {"steps": steps, "seconds": wall, "return": returns, "success": successes}


def final(folder: Path) -> dict | None:
    """The best policy's evaluation on the numpy env (results.json): return, success, wall seconds."""
    path = folder / "results.json"
    if not path.is_file():
        return None
    from agents.evaluate import jax_label

    results = json.loads(path.read_text())
    rows = (results.get("evaluation") or {}).get("policies", [])
    label = jax_label(folder)
    row = next((r for r in rows if r["policy"] == label), None)
    if row is None:
        return None
    return {"return": row["return_mean"], "success": row["success_rate"], "train": results["train_seconds"],
            "compile": results["compile_seconds"], "timesteps": results["timesteps"]}  # fmt: skip


# -- the spectrum -------------------------------------------------------------------------------------------------


def spectrum(env_id: str, policy_file: Path, steps: int, seed: int = UNSEEN, horizon: int = HORIZON) -> dict:
    """σ_max of the closed-loop step Jacobian along one deterministic episode (≤ steps) of the policy on the JAX
    env, the FTLE of its windows of `horizon` steps, and how often the action sits on its clip."""
    import jax
    import jax.numpy as jnp

    import connenv.jax
    from agents.jax_policy import JaxPolicy, flat_observation, forward, normalize
    from connenv.jax.namespace import JAX_TASK

    env, params = connenv.jax.make(env_id)
    policy = JaxPolicy(policy_file)
    pi = [(jnp.asarray(W), jnp.asarray(b)) for W, b in policy.pi]
    low, high = jnp.asarray(policy.low), jnp.asarray(policy.high)
    mean, var, clip = jnp.asarray(policy.obs_mean), jnp.asarray(policy.obs_var), policy.meta["clip_obs"]
    keys = policy.meta["obs_keys"]

    def raw_action(x):
        obs = env.env.observe(env.state_of(x[None]), JAX_TASK)
        obs = jax.tree_util.tree_map(lambda v: jnp.broadcast_to(v, (1, *jnp.shape(v)[1:])), obs)
        return forward(pi, normalize(flat_observation(obs, keys, jnp)[0], mean, var, clip, jnp), jnp)

    def closed_loop(x):
        return env.transition(x, jnp.clip(raw_action(x), low, high), params)[0]

    def step(carry, _):
        x, running = carry
        a = raw_action(x)
        J = jax.jacfwd(closed_loop)(x)
        x_next, _, _, terminated, _, failed = env.transition(x, jnp.clip(a, low, high), params)
        clipped = jnp.any((a <= low) | (a >= high))
        return (x_next, running & ~terminated & ~failed), (J, running, clipped)

    _, state = env.reset(jax.random.key(seed), params)
    (_, _), (J, running, clipped) = jax.jit(lambda x: jax.lax.scan(step, (x, True), None, steps))(state.x)
    J, running, clipped = np.asarray(J), np.asarray(running), np.asarray(clipped)
    length = int(running.sum())
    J = J[:length]
    sigma = np.linalg.svd(J, compute_uv=False)[:, 0]
    ftle = []
    for start in range(0, length - horizon + 1, max(horizon // 4, 1)):
        P, log_scale = np.eye(J.shape[1]), 0.0
        for Jt in J[start : start + horizon]:
            P = Jt @ P
            norm = np.linalg.norm(P)
            P, log_scale = P / norm, log_scale + math.log(norm)
        ftle.append((log_scale + math.log(np.linalg.svd(P, compute_uv=False)[0])) / horizon)
    return {"sigma": sigma, "ftle": np.array(ftle), "clipped": float(np.mean(clipped[:length])), "length": length,
            "dt": float(env.env.dt)}  # fmt: skip


# -- the page -----------------------------------------------------------------------------------------------------


def percent(values) -> str:
    values = [v for v in values if v is not None]
    if not values:
        return "–"
    return f"{np.mean(values):.0%} [{min(values):.0%}, {max(values):.0%}]"


def mean_of(values, fmt="{:.3g}") -> str:
    values = [v for v in values if v is not None]
    return fmt.format(np.mean(values)) if values else "–"


def first_reach(curve_list: list[dict | None], key: str, level: float = 0.9):
    """(steps, seconds) where the seeds' mean evaluation success first reaches `level`, or None."""
    curve_list = [c for c in curve_list if c is not None]
    if not curve_list:
        return None
    n = min(len(c["steps"]) for c in curve_list)
    mean = np.mean([c["success"][:n] for c in curve_list], 0)
    hit = np.nonzero(mean >= level)[0]
    if not len(hit):
        return None
    i = hit[0]
    return int(curve_list[0]["steps"][i]), float(np.nanmean([c["seconds"][i] for c in curve_list]))


def verdict(env_id: str, data: dict) -> str:
    """One sentence, from the figures: which method did better on this env and by what."""
    ppo, shac = data["ppo_jax"], data["shac_jax"]
    if shac["skipped"]:
        return f"{short(env_id)}: SHAC not run — reverse mode does not pass the step yet ({shac['skipped']})."
    s_ppo = [f["success"] for f in ppo["final"] if f]
    s_shac = [f["success"] for f in shac["final"] if f]
    r_ppo = [f["return"] for f in ppo["final"] if f]
    r_shac = [f["return"] for f in shac["final"] if f]
    if not s_ppo or not s_shac:
        return f"{short(env_id)}: incomplete (PPO {ppo['status']}, SHAC {shac['status']})."
    a, b = np.mean(s_shac), np.mean(s_ppo)
    reach = {algo: first_reach(data[algo]["curves"], "success") for algo in ALGOS}
    if a > b + 0.1:
        words = f"SHAC beats PPO on unseen episodes ({a:.0%} against {b:.0%})"
    elif b > a + 0.1:
        words = f"PPO beats SHAC on unseen episodes ({b:.0%} against {a:.0%})"
    elif np.mean(r_shac) > np.mean(r_ppo) + 0.05 * abs(np.mean(r_ppo)):
        words = f"both reach {b:.0%} / {a:.0%} (PPO / SHAC) success; SHAC's return is higher"
    elif np.mean(r_ppo) > np.mean(r_shac) + 0.05 * abs(np.mean(r_shac)):
        words = f"both reach {b:.0%} / {a:.0%} (PPO / SHAC) success; PPO's return is higher"
    else:
        words = f"a tie ({b:.0%} / {a:.0%} success, PPO / SHAC)"
    if reach["ppo_jax"] and reach["shac_jax"]:
        (sp, tp), (ss, ts) = reach["ppo_jax"], reach["shac_jax"]
        words += (f"; 90% evaluation success first at {ss:.3g} steps / {ts:.0f} s for SHAC against {sp:.3g} steps / "
                  f"{tp:.0f} s for PPO")  # fmt: skip
    elif reach["shac_jax"] or reach["ppo_jax"]:
        algo = "shac_jax" if reach["shac_jax"] else "ppo_jax"
        words += f"; only {NAMES[algo]} reached 90% evaluation success ({reach[algo][0]:.3g} steps)"
    return f"{short(env_id)}: {words}."


def spectrum_words(env_id: str, s: dict) -> str:
    sig, ftle = s["sigma"], s["ftle"]
    if not len(sig):
        return f"{short(env_id)}: no step."
    parts = [f"median σ_max {np.median(sig):.3g}, largest {sig.max():.3g}"]
    if len(ftle):
        growth = math.exp(HORIZON * ftle.max())
        parts.append(f"windows of {HORIZON} steps grow a gradient by up to {growth:.3g}× (largest FTLE "
                     f"{ftle.max():.3g} per step, mean {ftle.mean():.3g})")  # fmt: skip
        if ftle.max() * HORIZON > math.log(1e3):
            parts.append("exploding: a long window's gradient is dominated by the most unstable direction")
        elif ftle.max() < 0 and s["clipped"] < 0.5:
            parts.append("contracting: gradients through a window shrink, well conditioned")
    if s["clipped"] > 0.5:
        parts.append(f"the action sits on its clip on {s['clipped']:.0%} of the steps (zero gradient there)")
    elif s["clipped"] > 0:
        parts.append(f"action on its clip on {s['clipped']:.0%} of the steps")
    return f"{short(env_id)} ({s['length']} steps of {s['policy']}): " + "; ".join(parts) + "."


def chart(envs: list[str], data: dict, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(envs), 4, figsize=(17, 3.1 * len(envs)), squeeze=False)
    colors = {"ppo_jax": "tab:blue", "shac_jax": "tab:red"}
    for row, env_id in zip(axes, envs):
        for algo in ALGOS:
            for c in data[env_id][algo]["curves"]:
                if c is None:
                    continue
                kw = {"color": colors[algo], "alpha": 0.6, "lw": 1}
                row[0].plot(c["steps"], c["success"], **kw)
                row[1].plot(c["seconds"], c["success"], **kw)
                row[2].plot(c["steps"], c["return"], **kw)
            row[0].plot([], [], color=colors[algo], label=NAMES[algo])
        s = data[env_id].get("spectrum")
        if s is not None and len(s["sigma"]):
            t = np.arange(len(s["sigma"]))
            row[3].semilogy(t, s["sigma"], color="k", lw=1, label="σ_max(J_t)")
            if len(s["ftle"]):
                starts = np.arange(len(s["ftle"])) * max(HORIZON // 4, 1)
                row[3].semilogy(starts, np.exp(HORIZON * s["ftle"]), color="tab:orange", lw=1,
                                label=f"σ_max of {HORIZON}-step product")  # fmt: skip
            row[3].legend(fontsize=7)
        row[0].set_ylabel(short(env_id))
        row[0].legend(fontsize=7)
        for ax, title in zip(row, ("success vs env steps", "success vs wall s (training)", "return vs env steps",
                                   f"closed-loop Jacobian along a rollout ({s['policy'] if s else '–'})")):  # fmt: skip
            ax.set_title(title, fontsize=8)
            ax.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def page(envs: list[str], data: dict, seeds: int, quick: bool, command: str) -> str:
    lines = [
        "# Exact gradients: SHAC beside PPO",
        "",
        f"<!-- generated by `{command}`; do not edit -->",
        "",
        (
            "connenv.jax's step is differentiable, so a policy can learn from the gradient of the return itself, "
            "backpropagated through the physics, instead of PPO's likelihood-ratio estimate. `agents.jax_shac` runs SHAC "
            "(Xu et al., ICLR 2022: windows of 32 steps over 64 parallel envs, the actor's loss the window's return plus "
            "a learned critic's value at its end, Adam, gradient norm clipped to 1) and, with `--apg`, analytic policy "
            "gradients without a critic, compiled like the JAX PPO (`python train.py --backend jax`): one jit-ed update, "
            "seeds by vmap. Its policy files are the JAX PPO's, so `python -m agents.evaluate --policy jax:RUN` runs them "
            "on the numpy env."
        ),
        "",
        (
            f"Here both ran {seeds} seeds per env at the same budget of env steps on this 2-core machine (CPU, shared), "
            "each seed's best policy then evaluated on the numpy env on unseen episodes (reset seeds 100000 …). "
            "Success in the charts is the periodic evaluation on the JAX env (16 episodes per seed)."
        ),
        "",
        "```",
        "python -m agents.jax_shac --env connenv/Swing-v0 --seeds 5 --timesteps 300000 --runs runs",
        "python -m agents.evaluate --env connenv/Swing-v0 --policy jax:runs/Swing-v0_shac_jax_s0",
        "```",
        "",
    ]
    if quick:
        lines += [("**This page is from `--quick`** (2 envs, 2 seeds, 3·10⁴ steps): a check of the pipeline, not a "
                  "result."), ""]  # fmt: skip
    lines += ["## Where first-order beats PPO, and where not", ""]
    lines += [f"- {verdict(env_id, data[env_id])}" for env_id in envs]
    lines += ["", "## Unseen episodes (numpy env)", "",
              ("| env | steps / seed | PPO success [min, max over seeds] | SHAC success | PPO return | SHAC return | "
              "PPO wall s (train + compile) | SHAC wall s |"),
              "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for env_id in envs:
        d = data[env_id]
        cells = []
        for key in ("success", "return"):
            for algo in ALGOS:
                values = [f[key] for f in d[algo]["final"] if f]
                cells.append(percent(values) if key == "success" else mean_of(values))
        walls = []
        for algo in ALGOS:
            f = [x for x in d[algo]["final"] if x]
            walls.append(f"{f[0]['train']:.0f} + {f[0]['compile']:.0f}" if f else d[algo]["status"])
        lines.append(f"| {short(env_id)} | {d['steps']:.3g} | {' | '.join(cells)} | {' | '.join(walls)} |")
    lines += ["", (f"![SHAC and PPO, success and return against env steps and wall time; the Jacobian along a "
              f"rollout]({CHART})"), ""]  # fmt: skip
    lines += ["## The step Jacobian along a rollout", "",
              ("Backpropagation through a window multiplies the closed-loop step Jacobians "
              "J_t = ∂x_{t+1}/∂x_t (the physics' ∂f/∂x plus ∂f/∂u ∂π/∂x): where their product grows exponentially "
              "(chaos, a finite-time Lyapunov exponent λ_h > 0) the gradient explodes with the window and its "
              "variance swamps the signal; where a kink holds (an action on its clip, an end stop, the lift's "
              "floor in the swing-up's reward) it is zero and teaches nothing (Suh et al., ICML 2022). "
              f"Along one deterministic episode of the better trained policy (from reset seed {UNSEEN}), by "
              "`jax.jacfwd` (forward mode runs on every env):"), "",
              (f"| env | policy | steps | median σ_max(J_t) | max σ_max | mean λ_{HORIZON} | max λ_{HORIZON} | "
              f"growth over {HORIZON} steps (max) | action on its clip |"),
              "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for env_id in envs:
        s = data[env_id].get("spectrum")
        if s is None or not len(s["sigma"]):
            lines.append(f"| {short(env_id)} | – | – | – | – | – | – | – | – |")
            continue
        f = s["ftle"]
        ftle = f"{f.mean():.3g} | {f.max():.3g} | {math.exp(HORIZON * f.max()):.3g}" if len(f) else "– | – | –"
        lines.append(f"| {short(env_id)} | {s['policy']} | {s['length']} | {np.median(s['sigma']):.3g} | "
                     f"{s['sigma'].max():.3g} | {ftle} | {s['clipped']:.0%} |")  # fmt: skip
    lines += [""] + [f"- {spectrum_words(env_id, data[env_id]['spectrum'])}" for env_id in envs
                     if data[env_id].get("spectrum") is not None]  # fmt: skip
    lines += ["", "## Reverse mode", ""]
    for env_id in envs:
        error = data[env_id]["reverse"]
        lines.append(f"- {short(env_id)}: " + ("`jax.grad` runs through the step." if error is None else
                                                 f"`jax.grad` fails: `{error}`; SHAC waits for it."))  # fmt: skip
    lines += ["", "## What the gradient does at the step's kinks", "",
              ("- The action's clip to its bounds (in the env's step): zero derivative outside, so a sampled action "
              "beyond a bound teaches nothing about it."),
              "- End stops and one-sided min/max in the physics: the derivative of the branch taken.",
              ("- An episode's end inside a window: the autoreset's `where` passes no gradient into the new episode; "
              "the ended one contributes its partial return (plus the critic's value of its final observation where "
              "the clock cut it)."),
              ("- A floored reward (the log of the lift in Swing-v0 and KapitzaSwingUp-v0, floored at 1e-4): zero "
              "derivative below the floor."),
              ("- A failed step (held state, `info[\"stepper_failed\"]`) or any non-finite gradient: that seed's update "
              "is skipped and counted (`nonfinite` in progress.csv)."), ""]  # fmt: skip
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m agents.exact_gradients", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="2 envs, 2 seeds, 3·10⁴ steps: the pipeline only")
    parser.add_argument("--seeds", type=int, help="seeds per algorithm (default 5; --quick 2)")
    parser.add_argument("--runs", default=None, help="run folders (default runs/exact-gradients[-quick])")
    parser.add_argument("--envs", nargs="+", help="a subset of the envs")
    parser.add_argument("--retrain", action="store_true", help="train again where finished runs exist")
    parser.add_argument("--page", default=str(PAGE), help="the page to write (its chart beside it)")
    args = parser.parse_args(argv)
    import jax

    jax.config.update("jax_enable_x64", True)
    table = QUICK if args.quick else ENVS
    envs = args.envs or list(table)
    seeds = args.seeds or (2 if args.quick else 5)
    runs = Path(args.runs or ROOT / "runs" / ("exact-gradients-quick" if args.quick else "exact-gradients"))
    data = {}
    for env_id in envs:
        steps, episodes, spectrum_steps = table.get(env_id, (3e5, 100, 500))
        print(f"{env_id}:", flush=True)
        d = data[env_id] = {"steps": steps, "reverse": reverse_mode(env_id)}
        for algo in ALGOS:
            skipped = d["reverse"] if algo == "shac_jax" else None
            status = {"status": "skipped"} if skipped else train(env_id, algo, seeds, steps, episodes, runs,
                                                                  args.retrain)  # fmt: skip
            fs = folders(runs, env_id, algo, seeds)
            d[algo] = {"status": status["status"], "skipped": skipped, "curves": [curves(f) for f in fs],
                       "final": [final(f) for f in fs]}  # fmt: skip
        best = None  # the better algorithm's best seed on unseen episodes
        for algo in ALGOS:
            for folder, f in zip(folders(runs, env_id, algo, seeds), d[algo]["final"]):
                if f and (best is None or (f["success"], f["return"]) > best[0]):
                    best = ((f["success"], f["return"]), folder, algo)
        if best is not None:
            s = spectrum(env_id, best[1] / "best_policy.npz", spectrum_steps)
            d["spectrum"] = {**s, "policy": f"{NAMES[best[2]]} {best[1].name.rsplit('_', 1)[-1]}"}
            print("  " + spectrum_words(env_id, d["spectrum"]), flush=True)
        print("  " + verdict(env_id, d), flush=True)
    out = Path(args.page)
    out.parent.mkdir(parents=True, exist_ok=True)
    chart(envs, data, out.parent / (out.stem + ".png"))
    command = "python -m agents.exact_gradients" + (" --quick" if args.quick else "")
    command += f" --envs {' '.join(envs)}" if args.envs else ""
    text = page(envs, data, seeds, args.quick, command).replace(f"]({CHART})", f"]({out.stem}.png)")
    out.write_text(text)
    print(f"wrote {out} and {out.stem}.png")


if __name__ == "__main__":
    main()
