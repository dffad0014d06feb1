"""The open challenges' page (agents.challenges) says what the run folders hold: a challenge is learned only where the
seeds' mean success on the unseen episodes reaches 90% at 10⁸ steps, a run killed before its end shows its curves to
its last checkpoint, and the attempts and the first-order result sit beside the budget's run."""

from __future__ import annotations

import csv
import json

import numpy as np

from agents import challenges
from agents.evaluate import jax_label


def run_folder(runs, name, steps, success, results=True, seconds=60.0):
    folder = runs / name
    folder.mkdir(parents=True)
    checkpoints = np.linspace(steps / 4, steps, 4).astype(int)
    np.savez(folder / "evaluations.npz", timesteps=checkpoints, results=np.zeros((4, 2)),
             successes=np.full((4, 2), success))  # fmt: skip
    with open(folder / "progress.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=["timesteps", "seconds", "episodes", "success"])
        writer.writeheader()
        writer.writerows({"timesteps": s, "seconds": seconds * (i + 1) / 4, "episodes": 10, "success": success}
                         for i, s in enumerate(checkpoints))  # fmt: skip
    if results:
        policies = [{"policy": jax_label(folder), "success_rate": success, "return_mean": 1.0},
                    {"policy": "analytic", "success_rate": 1.0, "return_mean": 3.9}]  # fmt: skip
        (folder / "results.json").write_text(json.dumps({
            "status": "finished", "timesteps": int(steps), "train_seconds": seconds, "compile_seconds": 1.0,
            "evaluation": {"policies": policies}}))  # fmt: skip
    return folder


def test_the_page_calls_a_challenge_learned_only_at_ninety_percent_and_ten_to_the_eight_steps(tmp_path):
    runs = tmp_path / "runs"
    for s, success in enumerate([1.0, 0.9, 0.85]):  # mean 92%, but short of 10⁸ steps: still open
        run_folder(runs, f"KapitzaSwingUp-v0_ppo_jax_s{s}", 5e7, success)
    for s in range(2):  # killed before the end: no results.json
        run_folder(runs, f"RollingBallPose-v0_ppo_jax_s{s}", 3e7, 0.0, results=False)
    for s in range(2):  # the curriculum's attempt: 95% at 10⁸
        run_folder(runs / "curriculum", f"KapitzaSwingUp-v0_ppo_jax_s{s}", 1e8, 0.95)
    first = tmp_path / "eg"
    for algo, success in (("ppo_jax", 0.0), ("shac_jax", 0.25)):
        run_folder(first, f"KapitzaSwingUp-v0_{algo}_s0", 2e5, success)
    path = tmp_path / "challenges.md"
    text = challenges.main(["--runs", str(runs), "--write", str(path), "--first-order-runs", str(first)])
    kapitza, pose, tried = (text.split("## RollingBallPose-v0")[0], text.split("## RollingBallPose-v0")[1].split(
        "## What the literature")[0], text.split("## What the literature suggests, tried")[1])  # fmt: skip
    assert "**Open**: over 3 seeds at 50,000,000 steps each, 92% of the unseen episodes succeed" in kapitza
    assert "the analytic controller on the same episodes: 100%, return 3.9" in kapitza
    assert "| SHAC | 2e+05 | 25% [25%, 25%] |" in kapitza and "| PPO | 2e+05 | 0% [0%, 0%] |" in kapitza
    assert "No seed has been evaluated" in pose and pose.count("stopped without results.json") == 2
    assert "30,000,000" in pose and "First-order" not in pose  # no SHAC runs of this env in the folder
    assert "**Learned**: over 2 seeds at 100,000,000 steps each, 95%" in tried and "kapitza_release" in tried
    assert "| 0 | finished | 100,000,000 | 1.0 | 95.0% | 95% | 95% | 1 |" in tried  # the training episodes' success too
    assert path.with_suffix(".png").is_file() and path.read_text() == text
