"""Bad input at every boundary (issue 16): reset states and make kwargs out of range, actions that are no real
array, clones of a rendered env, negative seeds on the command lines, the benchmark's help, the goal env under
SB3's checker and HER, and the test extra."""

from __future__ import annotations

import copy
import pickle
import re

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv import examples

IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))


def make(env_id, **extra):
    kwargs = examples.MAKE_KWARGS[env_id]() if env_id in examples.MAKE_KWARGS else {}
    return gym.make(env_id, **kwargs, **extra)


# -- item 2: a rendered env pickles and deep-copies ------------------------------------------------------------


CLONES = {"deepcopy": copy.deepcopy, "pickle": lambda env: pickle.loads(pickle.dumps(env))}


@pytest.mark.parametrize("clone", CLONES.values(), ids=CLONES.keys())
def test_a_rendered_env_clones_without_its_renderer_and_the_clone_renders_anew(clone):
    env = gym.make("connenv/Swing-v0", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    twin = clone(env)
    assert twin.unwrapped._renderer is None and env.unwrapped._renderer is not None
    assert np.array_equal(twin.render(), frame)
    env.close()
    twin.close()


# -- item 5: messages that name the thing ----------------------------------------------------------------------


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("bad", [5, "x", [1.0]], ids=["int", "str", "list"])
def test_a_reset_state_that_is_no_mapping_is_refused_naming_it(env_id, bad):
    env = make(env_id)
    with pytest.raises(ValueError, match=r"options\['state'\]=.* must be a mapping"):
        env.reset(options={"state": bad})
    with pytest.raises(ValueError, match=r"reset options=.* must be a mapping"):
        env.reset(options=bad)


@pytest.mark.parametrize("env_id", IDS)
def test_string_and_complex_actions_are_refused_naming_the_action(env_id):
    env = make(env_id)
    env.reset(seed=0)
    size = env.action_space.shape[0]
    with pytest.raises(ValueError, match=r"action=.*'a'.* must be real numbers"):
        env.step(["a"] * size)
    with pytest.raises(ValueError, match=r"action=.*j\]\) is complex"):
        env.step(np.full(size, 0.5 + 1j))
    vector = gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point", **make(env_id).spec.kwargs)
    vector.reset(seed=0)
    with pytest.raises(ValueError, match="is complex"):
        vector.step(np.full((2, size), 0.5 + 1j))


@pytest.mark.parametrize(
    ("env_id", "names"),
    [
        ("connenv/RollingBallPose-v0", ["position_tolerance", "radius", "v_max", "dt", "tolerance", "integrator"]),
        ("connenv/KapitzaSwingUp-v0", ["hold_time", "pivot", "v_max", "a_max", "dt", "tolerance", "integrator"]),
        ("connenv/Swing-v0", ["r_min", "r_max", "dt", "integrator", "substeps"]),
    ],
)
def test_an_unknown_kwarg_lists_every_valid_name_of_the_class_and_its_bases(env_id, names):
    with pytest.raises(ValueError, match="unknown parameter") as error:
        gym.make(env_id, nosuch=1.0)
    valid = error.value.args[0].split("valid: ")[1]
    for name in names:
        assert f"'{name}'" in valid
    assert "'kwargs'" not in valid and "'stepper_options'" not in valid


# -- item 3: a negative seed is an argparse error --------------------------------------------------------------


def test_a_negative_seed_is_a_usage_error_of_evaluate_and_train(train, capsys):
    from agents import evaluate

    for parse in (evaluate.parse_args, train.parse_args):
        for flag in ("--seed", "--eval-seed") if parse is train.parse_args else ("--seed",):
            with pytest.raises(SystemExit) as exit_:
                parse([flag, "-1"])
            assert exit_.value.code == 2
            assert f"argument {flag}: '-1' is not a seed" in capsys.readouterr().err
    assert evaluate.parse_args(["--seed", "0"]).seed == 0


# -- item 4: the benchmark's command line lists its subcommands ------------------------------------------------


def test_bench_help_lists_every_subcommand_and_no_arguments_prints_it(capsys):
    from connenv import bench

    bench.main([])
    listing = capsys.readouterr().out
    for command in ("all", "precision", "stability", "steppers", "generic"):
        assert re.search(rf"^    {command}\b", listing, re.MULTILINE)
    with pytest.raises(SystemExit):
        bench.main(["--help"])
    assert capsys.readouterr().out == listing
    with pytest.raises(SystemExit) as exit_:
        bench.main(["nosuch"])
    assert exit_.value.code == 2 and "invalid choice: 'nosuch'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        bench.main(["precision", "--help"])
    assert "--quick" in capsys.readouterr().out
