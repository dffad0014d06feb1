"""The canvas under its former name, connenv.envs.rendering, for the builders and for a user's ``draw(state, canvas)``
written against it; connenv.rendering holds it and every env's renderer."""

from connenv.rendering import SIZE, Canvas, CoordinatePlot

__all__ = ["SIZE", "Canvas", "CoordinatePlot"]
