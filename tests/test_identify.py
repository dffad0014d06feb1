"""System identification on the model: 1,000 random-policy steps of an env with unknown parameters recover them."""

from __future__ import annotations

import numpy as np
import pytest

from agents.identify import identify, main, transitions

CASES = [
    ("connenv/Swing-v0", {"g": 7.3, "mass": 1.8}),
    ("connenv/BeadOnBar-v1", {"g": 5.1, "mass": 0.6}),
    ("connenv/KapitzaPendulum-v0", {"length": 0.7, "g": 11.2}),
    ("connenv/Skier-v0", {"g": 8.1, "mass": 55.0}),
    ("connenv/ElroysBeanie-v0", {"body_inertia": 1.7}),
    ("connenv/KozlovShell-v0", {"mass": 0.3}),
]


@pytest.mark.parametrize(("env_id", "true"), CASES, ids=[c[0] for c in CASES])
def test_the_parameters_are_recovered_to_one_percent(env_id, true):
    fitted = identify(env_id, transitions(env_id, true, 1000), list(true))
    for name, value in true.items():
        assert fitted[name] == pytest.approx(value, rel=0.01)


def test_noisy_measurements_still_give_the_parameters_to_one_percent():
    """x′ measured with Gaussian noise of 1% of each entry's change per step."""
    x, a, x_next = transitions("connenv/Swing-v0", {"g": 7.3, "mass": 1.8}, 1000)
    noise = np.random.default_rng(0).normal(0.0, 0.01, x_next.shape) * np.std(x_next - x, axis=0)
    fitted = identify("connenv/Swing-v0", (x, a, x_next + noise), ["g", "mass"])
    assert fitted["g"] == pytest.approx(7.3, rel=0.01) and fitted["mass"] == pytest.approx(1.8, rel=0.01)


def test_the_command_line_names_a_bad_parameter_in_one_line(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["--env", "connenv/Swing-v0", "--true", "g=-1"])
    assert exit.value.code == 2 and capsys.readouterr().err.count("\n") == 1
