"""What every connenv task shares: the render_mode check, lazy pygame rendering and closing, as in classic control;
StepperErrors that name the env's dt and parameters."""

from __future__ import annotations

import gymnasium as gym

from connenv.core.steppers import StepperError


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

    def _stepper_error(self, error: StepperError) -> StepperError:
        """`error` (a stepper's, or the env's own invariant check) with the env, the time, dt and the physical
        parameters (the subclass's ``parameters()``) added: ``raise self._stepper_error(error) from error``."""
        values = ", ".join(f"{key} = {value!r}" for key, value in self.parameters().items())
        where = f"{type(self).__name__} in the step from t = {self.t:.6g} s, dt = {self.dt}"
        return StepperError(f"{error} [{where}, {values}]")
