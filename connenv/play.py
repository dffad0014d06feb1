"""Play an env by hand: ``python -m connenv.play ENV_ID`` opens it in a pygame window.

The keyboard (and, for the rolling ball and the tube, the mouse) sets the action; the window shows the env's own
rendering, the step, the reward, the return and the success. Pump the swing with the space bar: held, the child
stands (the radius shortens to r_min), released, squats (r_max) — stand at the bottom, squat at the ends. Roll the
ball, or bend the tube, by moving the mouse: its motion in a frame is the rolling (bending) velocity, so a loop of the
mouse turns the ball by the holonomy of the loop, Lawton's "rotate a rigid body by moving a computer mouse".
Every other env: the arrow keys, ←/→ on the first action and ↓/↑ on the second, held for ±1, released for 0.

R resets, Esc or Q quits; an episode's end shows its outcome, and the next key (or a second) starts a new one.

    python -m connenv.play ENV_ID [--seed 0] [--scale 1.5] [--kwargs dt=0.02 ...] [--fast] [--frames N]
                                  [--screenshot window.png]    # ENV_ID: a connenv id (--help lists them)

``Player`` holds everything but the window (events in, action and text out), so that it runs headless too.
"""

from __future__ import annotations

import argparse
import ast

import gymnasium as gym
import numpy as np

import connenv  # noqa: F401  (registers the envs)
from connenv import cli
from connenv.envs.spec import spec

PROG = "python -m connenv.play"
# How an env's action is set by hand is its spec's `play`: "space" (pumped with the space bar: held, the spec's
# space_action, the swing's child standing at r_min or the skier rising to h_max; released, the opposite end),
# "mouse" (its motion over a frame, MOUSE_SPEED pixels for a full action, is the action) or "arrows".
MOUSE_SPEED = 12.0
ARROWS = (("K_LEFT", "K_RIGHT"), ("K_DOWN", "K_UP"))
"""The keys for −1 and +1 of each action component."""
HELP = {"space": "space: stand / release: squat", "mouse": "move the mouse to roll", "arrows": "arrow keys"}
PAUSE = 1.0
STRIP_PAD = 10  # pixels of white around the help lines, in their strip below the frame
"""Seconds an episode's outcome stays on screen before the next episode (a key starts it at once)."""


def env_ids() -> list[str]:
    return sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))


def controls(env_id: str) -> str:
    """'space', 'mouse' or 'arrows': how env_id's action is set by hand."""
    return spec(env_id).play


class Player:
    """An env played by hand: ``handle(event)`` takes pygame events, ``tick()`` steps with the action they make,
    ``frame()`` and ``lines()`` are what the window shows."""

    def __init__(self, env_id: str, seed: int | None = None, env_kwargs: dict | None = None):
        import pygame

        if env_id not in env_ids():
            raise ValueError(f"unknown env {env_id!r}; the connenv ids are {env_ids()}")
        self.pygame, self.env_id, self.controls = pygame, env_id, controls(env_id)
        kwargs = {**spec(env_id).make_kwargs(), **(env_kwargs or {})}
        self.env = gym.make(env_id, render_mode="rgb_array", **kwargs)
        self.fps = self.env.metadata["render_fps"]
        self.held: set[int] = set()
        self.motion = np.zeros(2)
        self.running = True
        self.reset(seed)

    def reset(self, seed: int | None = None):
        self.observation, self.info = self.env.reset(seed=seed)
        self.steps, self.reward, self.total, self.outcome, self.pause = 0, 0.0, 0.0, None, 0

    def handle(self, event) -> None:
        pygame = self.pygame
        if event.type == pygame.QUIT or (event.type == pygame.KEYDOWN and event.key in (pygame.K_ESCAPE, pygame.K_q)):
            self.running = False
        elif event.type == pygame.KEYDOWN:
            self.held.add(event.key)
            if event.key == pygame.K_r or self.outcome is not None:
                self.reset()
        elif event.type == pygame.KEYUP:
            self.held.discard(event.key)
        elif event.type == pygame.MOUSEMOTION:
            self.motion += (event.rel[0], -event.rel[1])  # screen y points down

    def action(self) -> np.ndarray:
        """The action the held keys (or the mouse's motion since the last tick) make."""
        pygame, space = self.pygame, self.env.action_space
        if self.controls == "space":
            pumped = spec(self.env_id).space_action
            return np.full(space.shape, pumped if pygame.K_SPACE in self.held else -pumped, np.float32)
        if self.controls == "mouse":
            return np.clip(self.motion[: space.shape[0]] / MOUSE_SPEED, -1.0, 1.0).astype(np.float32)
        keys = [(getattr(pygame, low) in self.held, getattr(pygame, high) in self.held) for low, high in ARROWS]
        return np.array([float(high) - float(low) for low, high in keys[: space.shape[0]]], np.float32)

    def tick(self) -> None:
        """One step with the action, or, after an episode's end, one frame of its outcome (then a new episode)."""
        if self.outcome is not None:
            self.pause += 1
            if self.pause >= PAUSE * self.fps:
                self.reset()
            return
        action = self.action()
        self.motion[:] = 0.0
        self.observation, self.reward, terminated, truncated, self.info = self.env.step(action)
        self.steps, self.total = self.steps + 1, self.total + float(self.reward)
        if terminated or truncated:
            success = bool(self.info.get("is_success", False))
            self.outcome = "success" if success else "time is up" if truncated else "ended"

    def lines(self) -> list[str]:
        """The text over the picture: the env, the step, the reward and return, the success, the keys."""
        success = bool(self.info.get("is_success", False))
        status = f"episode over: {self.outcome}" if self.outcome else f"success: {'yes' if success else 'no'}"
        return [
            f"{self.env_id}  step {self.steps}  reward {float(self.reward):+.3f}  return {self.total:+.3f}",
            f"{status}   {HELP[self.controls]}, R reset, Esc quit",
        ]

    def frame(self) -> np.ndarray:
        return self.env.render()

    def close(self):
        self.env.close()


def parse_kwargs(pairs: list[str]) -> dict:
    """key=value pairs, each value a Python literal (a bare word is a string)."""
    kwargs = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"--kwargs {pair!r}: expected key=value")
        try:
            kwargs[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            kwargs[key] = value
    return kwargs


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("env_id", metavar="ENV_ID", choices=env_ids(), help="a connenv id")
    parser.add_argument("--seed", type=cli.seed_int, help="of the first episode")
    parser.add_argument(
        "--scale", type=cli.positive_float, default=1.0, help="of the window against the env's 500-pixel frame"
    )
    parser.add_argument("--kwargs", nargs="*", default=[], metavar="KEY=VALUE", help="the env's make kwargs")
    parser.add_argument("--fast", action="store_true", help="as fast as possible, not at the env's frame rate")
    parser.add_argument(
        "--frames", type=cli.positive_int, help="quit after this many frames (a scripted or headless run)"
    )
    parser.add_argument(
        "--screenshot", type=cli.writable_file, metavar="PNG", help="save the window to this file at each frame"
    )
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> Player:
    """Open the window and play until quit (or --frames); return the player (its env closed)."""
    import pygame

    args = parse_args(argv)
    try:
        player = Player(args.env_id, args.seed, parse_kwargs(args.kwargs))
    except (ValueError, TypeError) as error:  # the env's refusal of the kwargs, named as given
        raise ValueError(f"{args.env_id} refuses --kwargs {' '.join(args.kwargs) or '(none)'}: {error}") from error
    size = tuple(round(args.scale * n) for n in player.frame().shape[1::-1])
    pygame.font.init()
    font, clock = pygame.font.Font(None, 22), pygame.time.Clock()
    strip = STRIP_PAD + font.get_linesize() * len(player.lines())  # the help's own strip, below the env's frame:
    try:  # the frame's caption (t, r, ...) stays as the env drew it
        pygame.display.init()
        width = max(size[0], 12 + max(font.size(line)[0] for line in player.lines()))  # a small --scale: the help whole
        screen = pygame.display.set_mode((width, size[1] + strip))
    except pygame.error as error:  # no display: the machine's, not a bug, so an OSError that cli.run reports
        player.close()
        raise OSError(f"no display for the window (SDL: {error}); to run headless: SDL_VIDEODRIVER=dummy") from error
    pygame.display.set_caption(f"connenv: {args.env_id}")
    frames = 0
    while player.running and (args.frames is None or frames < args.frames):
        for event in pygame.event.get():
            player.handle(event)
        player.tick()
        picture = pygame.surfarray.make_surface(np.ascontiguousarray(player.frame().swapaxes(0, 1)))
        screen.fill((255, 255, 255))
        screen.blit(picture if picture.get_size() == size else pygame.transform.smoothscale(picture, size), (0, 0))
        for row, line in enumerate(player.lines()):
            screen.blit(font.render(line, True, (0, 0, 0)), (6, size[1] + STRIP_PAD // 2 + font.get_linesize() * row))
        pygame.display.flip()
        if args.screenshot:
            pygame.image.save(screen, args.screenshot)
        clock.tick(0 if args.fast else player.fps)
        frames += 1
    player.close()
    pygame.quit()
    return player


if __name__ == "__main__":
    cli.run(main, PROG)
