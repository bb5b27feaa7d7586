"""The physics of a sweep: the pendulum, its parameters and the effects acting on it.

``PARAMETERS`` and ``PARAMETER_INFO`` are computed on access (an effect registered
later adds its parameters); code inside sweep calls `parameter_names` and
`parameter_info`.
"""

from .coupled import CoupledPendula
from .declared import DeclaredSystem
from .double import DoublePendulum
from .effect import EFFECTS, Drive, Effect, EffectDeclaration, Parameter, register, unregister
from .effects import Damping, Forcing, PivotDrive, QuadraticDrag, Torque
from .network import SwingNetwork
from .scene import (
    BASE_PARAMETERS,
    MODELS,
    Scene,
    parameter_info,
    parameter_names,
    parameter_table,
    parameters,
)
from .system import Coordinate, SystemDeclaration

__all__ = ["BASE_PARAMETERS", "Coordinate", "CoupledPendula", "Damping", "DeclaredSystem",
           "DoublePendulum", "Drive",
           "EFFECTS", "Effect", "EffectDeclaration",
           "Forcing", "MODELS", "PARAMETERS", "PARAMETER_INFO", "Parameter", "PivotDrive",
           "QuadraticDrag", "Scene", "SwingNetwork", "SystemDeclaration", "Torque",
           "parameter_info", "parameter_names",
           "parameter_table", "parameters", "register", "unregister"]


def __getattr__(name):
    if name == "PARAMETERS":
        return parameter_names()
    if name == "PARAMETER_INFO":
        return parameter_info()
    raise AttributeError(f"module 'sweep.physics' has no attribute {name!r}")
