"""The physics of a sweep: the pendulum, its parameters and the effects acting on it."""

from .scene import MODELS, PARAMETER_INFO, PARAMETERS, Damping, Forcing, Scene

__all__ = ["Damping", "Forcing", "MODELS", "PARAMETERS", "PARAMETER_INFO", "Scene"]
