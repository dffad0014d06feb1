"""What every connenv task shares: the render_mode check, lazy pygame rendering and closing, as in classic control."""

from __future__ import annotations

import gymnasium as gym


class RenderedEnv(gym.Env):
    """A Gymnasium env whose subclasses give ``_make_renderer()`` and ``_draw(renderer)``; pygame loads on first render."""

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, render_mode: str | None, dt: float):
        """dt: the control step, s (checked by the subclass); it sets the render frame rate."""
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode={render_mode!r} is not one of {self.metadata['render_modes']} or None")
        self.render_mode = render_mode
        self.dt = dt
        self.metadata = {**self.metadata, "render_fps": round(1.0 / dt)}
        self._renderer = None

    def render(self):
        if self.render_mode is None:
            gym.logger.warn('render() without render_mode; pass render_mode="rgb_array" or "human" to make().')
            return None
        if self._renderer is None:
            self._renderer = self._make_renderer()
        return self._draw(self._renderer)

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
