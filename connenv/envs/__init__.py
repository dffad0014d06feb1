"""Gymnasium tasks, one module per environment."""
