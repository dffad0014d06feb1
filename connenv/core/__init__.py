"""Mechanics of active constraints (Bressan) and the steppers that integrate them."""

from connenv.core.integrators import make_stepper
from connenv.core.mechanics import JumpClass, bressan_matrices, classify, hamiltonian, vector_field
from connenv.core.steppers import StepperError

__all__ = ["JumpClass", "StepperError", "bressan_matrices", "classify", "hamiltonian", "make_stepper", "vector_field"]
