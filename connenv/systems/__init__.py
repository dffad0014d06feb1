"""Mechanical systems, one module per system: metric, potential, vector fields, exact flows."""
