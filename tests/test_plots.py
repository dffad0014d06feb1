"""agents.plots through agents.evaluate: ``--plot`` draws a readable PNG of its expected size for every registered
id (short episodes, so that each draw stays fast), and refuses a path that is not a writable .png in one line."""

from __future__ import annotations

import pytest
from matplotlib import image

from agents import plots
from agents.controllers import CONTROLLERS
from agents.evaluate import Trace, evaluate, main, make_policy
from connenv.envs.spec import registry

STEPS = 20  # per episode: enough for a path, a cycle's worth of events, few enough for a fast test


def kwargs_of(env_id: str) -> dict:
    return {**registry[env_id].make_kwargs(), "max_episode_steps": STEPS}


@pytest.mark.parametrize("env_id", list(registry))
def test_plot_every_env(env_id, tmp_path):
    """The reference controller's episode (random where the env has none) beside a random one."""
    kwargs = kwargs_of(env_id)
    specs = ["analytic", "random"] if env_id in CONTROLLERS else ["random"]
    traces = {}
    for spec in specs:
        label, policy = make_policy(spec, env_id, 0, env_kwargs=kwargs)
        traces[label] = Trace()
        evaluate(env_id, policy, 1, 0, env_kwargs=kwargs, trace=traces[label])
    assert all(len(trace.states) == len(trace.actions) + 1 == len(trace.infos) for trace in traces.values())
    path = tmp_path / "plot.png"
    width, height = plots.draw(env_id, traces, path, kwargs)
    assert path.stat().st_size > 0
    assert image.imread(path).shape[:2] == (height, width)


def test_cli_plot(tmp_path, capsys):
    path = tmp_path / "figures" / "swing.png"
    main(["--env", "connenv/Swing-v0", "--policy", "analytic", "random", "--episodes", "2", "--plot", str(path),
          "--json", str(tmp_path / "eval.json"), "--env-kwargs", f'{{"max_episode_steps": {STEPS}}}'])  # fmt: skip
    width, height = 2 * plots.PANEL[0], 2 * plots.PANEL[1]  # two policies side by side over the energy
    assert image.imread(path).shape[:2] == (round(height * plots.DPI), round(width * plots.DPI))
    assert str(path) in capsys.readouterr().out


@pytest.mark.parametrize("name, reason", [("plot.svg", "does not end in .png"), ("file/plot.png", "is a file")])
def test_cli_plot_bad_path(tmp_path, capsys, name, reason):
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit) as exit_:
        main(["--env", "connenv/Swing-v0", "--plot", str(tmp_path / name)])
    error = capsys.readouterr().err
    assert exit_.value.code == 2 and reason in error and len(error.strip().splitlines()) == 1


def test_cli_plot_keeps_the_default_report_and_says_what_it_draws(tmp_path, monkeypatch):
    """--plot wrote runs/eval_{env}_s{seed}.json, over the README's 100-episode report: its report goes beside the
    figure. The title says which episode is drawn; the legend lists only marks that are drawn."""
    from matplotlib.figure import Figure

    figures = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *args, **kwargs: figures.append(self))
    monkeypatch.chdir(tmp_path)
    main(["--env", "connenv/Swing-v0", "--policy", "random", "--episodes", "2", "--seed", "5", "--plot", "swing.png",
          "--env-kwargs", '{"max_episode_steps": 2}'])  # fmt: skip
    assert not (tmp_path / "runs").exists() and (tmp_path / "swing.json").is_file()
    (figure,) = figures
    assert "first episode (reset seed 5, of 2 evaluated)" in figure.get_suptitle()
    drawn = {line.get_marker() for axes in figure.axes for line in axes.get_lines() if len(line.get_xdata())}
    for legend in figure.legends:
        for handle in legend.legend_handles:
            marker = handle.get_marker() if hasattr(handle, "get_marker") else "None"
            assert marker in ("None", "", None) or marker in drawn, handle.get_label()


def test_the_swings_axes_carry_their_units(tmp_path, monkeypatch):
    """The phase portrait's axes and the energy's are labelled with SI units (θ in rad, p in kg m²/s, the radius
    r in m, the energy in J), as the env's reset state declares them."""
    from matplotlib.figure import Figure

    figures = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *args, **kwargs: figures.append(self))
    monkeypatch.chdir(tmp_path)
    main(["--env", "connenv/Swing-v0", "--policy", "random", "--episodes", "1", "--plot", "swing.png",
          "--env-kwargs", '{"max_episode_steps": 5}'])  # fmt: skip
    (figure,) = figures
    labels = {label for axes in figure.axes for label in (axes.get_xlabel(), axes.get_ylabel()) if label}
    assert {"theta (rad)", "p (kg m²/s)", "t (s)", "energy (J)", "u = r (m)"} <= labels, labels
