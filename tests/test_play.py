"""connenv.play, headless (SDL's dummy video driver): synthetic pygame events set the action, as keys and a mouse
would; every registered id plays a few frames and shows its reward and success."""

from __future__ import annotations

import os

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import numpy as np
import pygame
import pytest

from connenv import play


def key(kind, name):
    return pygame.event.Event(kind, key=getattr(pygame, name))


def test_the_space_bar_pumps_the_swing():
    """Held: the child stands (r_min); released: squats (r_max) — the radius follows within the step."""
    player = play.Player("connenv/Swing-v0", seed=0)
    swing = player.env.unwrapped
    player.handle(key(pygame.KEYDOWN, "K_SPACE"))
    player.tick()
    assert swing.state.r == pytest.approx(swing.r_min)
    player.handle(key(pygame.KEYUP, "K_SPACE"))
    player.tick()
    assert swing.state.r == pytest.approx(swing.r_max)


def test_a_mouse_motion_rolls_the_ball_the_way_the_mouse_went():
    """Moving the mouse right (screen x) and up (screen −y) rolls the contact point along +x and +y."""
    player = play.Player("connenv/RollingBall-v0", seed=0)

    def position():
        return np.array([player.info["state"]["x"], player.info["state"]["y"]], float)

    before = position()
    player.handle(pygame.event.Event(pygame.MOUSEMOTION, rel=(6, 0), pos=(0, 0), buttons=(0, 0, 0)))
    assert player.action() == pytest.approx([0.5, 0.0])
    player.tick()
    moved = position() - before
    assert moved[0] > 0 and abs(moved[1]) < 1e-12
    player.handle(pygame.event.Event(pygame.MOUSEMOTION, rel=(0, -30), pos=(0, 0), buttons=(0, 0, 0)))
    assert player.action() == pytest.approx([0.0, 1.0])  # clipped to the space
    player.tick()
    assert player.action() == pytest.approx([0.0, 0.0])  # no motion since the last frame: the ball rests


def test_the_arrow_keys_set_each_component_while_held():
    player = play.Player("connenv/KozlovShell-v0", seed=0)
    player.handle(key(pygame.KEYDOWN, "K_RIGHT"))
    player.handle(key(pygame.KEYDOWN, "K_DOWN"))
    assert player.action() == pytest.approx([1.0, -1.0])
    player.handle(key(pygame.KEYUP, "K_RIGHT"))
    assert player.action() == pytest.approx([0.0, -1.0])


@pytest.mark.parametrize("env_id", play.env_ids())
def test_every_env_plays_in_a_window_and_shows_reward_and_success(env_id, tmp_path):
    """Three frames of main() in the dummy window: the text names the step, the reward and the success, over the
    env's picture (the saved window is not one colour)."""
    shot = tmp_path / "window.png"
    player = play.main([env_id, "--seed", "1", "--fast", "--frames", "3", "--scale", "0.5", "--screenshot", str(shot)])
    assert player.steps == 3 and player.running
    text = "\n".join(player.lines())
    assert f"{env_id}  step 3  reward " in text and "return " in text and "success: " in text
    pixels = pygame.surfarray.array3d(pygame.image.load(shot))
    assert pixels.shape[1] > 250 and len(np.unique(pixels[:250, :250].reshape(-1, 3), axis=0)) > 10  # the help below


def test_r_resets_and_escape_quits():
    player = play.Player("connenv/Skier-v0", seed=0)
    for _ in range(4):
        player.tick()
    assert player.env.unwrapped.state.t > 0
    player.handle(key(pygame.KEYDOWN, "K_r"))
    assert player.env.unwrapped.state.t == 0.0 and player.steps == 0
    player.handle(key(pygame.KEYDOWN, "K_ESCAPE"))
    assert not player.running


def test_an_episode_end_shows_its_outcome_then_starts_anew():
    player = play.Player("connenv/Swing-v0", seed=0, env_kwargs={"max_episode_steps": 2})
    player.tick()
    player.tick()
    assert player.outcome == "time is up" and "episode over: time is up" in player.lines()[1]
    for _ in range(round(play.PAUSE * player.fps)):
        player.tick()
    assert player.outcome is None and player.steps == 0


def test_unknown_ids_and_bad_kwargs_are_refused_by_name(capsys):
    with pytest.raises(ValueError, match=r"unknown env 'connenv/Nope-v0'; the connenv ids are \[.*Swing-v0"):
        play.Player("connenv/Nope-v0")
    with pytest.raises(SystemExit):
        play.main(["connenv/Nope-v0"])
    assert "argument ENV_ID: invalid choice: 'connenv/Nope-v0'" in capsys.readouterr().err
    with pytest.raises(ValueError, match="--kwargs 'dt': expected key=value"):
        play.parse_kwargs(["dt"])
    assert play.parse_kwargs(["dt=0.02", "surface=plane"]) == {"dt": 0.02, "surface": "plane"}


def test_the_help_lines_leave_the_envs_frame_and_caption_as_drawn(monkeypatch, tmp_path):
    """The window is the env's frame with the help in a strip below it: the frame's own caption (t, r) is not
    drawn over, in the window or its --screenshot."""
    frames = []
    drawn = play.Player.frame
    monkeypatch.setattr(play.Player, "frame", lambda player: frames.append(drawn(player)) or frames[-1])
    path = tmp_path / "window.png"
    play.main(["connenv/Swing-v0", "--seed", "0", "--frames", "2", "--fast", "--screenshot", str(path)])
    window = pygame.surfarray.array3d(pygame.image.load(str(path))).swapaxes(0, 1)
    height = frames[-1].shape[0]
    assert window.shape[0] > height  # the help's strip
    np.testing.assert_array_equal(window[:height, : frames[-1].shape[1]], frames[-1])
    assert np.any(window[height:] < 128)  # the help, written in it


def test_the_swings_reachable_band_is_labelled():
    """The shaded band of reachable radii carries its label (drawn in the band's text colour above the pivot)."""
    import gymnasium as gym

    env = gym.make("connenv/Swing-v0", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    env.close()
    label = np.all(frame == (90, 90, 120), axis=-1)
    rows = np.flatnonzero(label.any(axis=1))
    assert label.sum() > 50 and rows.max() < frame.shape[0] / 2  # text, over the pivot
