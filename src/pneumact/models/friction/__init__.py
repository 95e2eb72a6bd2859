"""Friction laws behind one interface (``base``): LuGre, Dahl, Bouc-Wen, elasto-plastic,
generalized Maxwell-slip and two static maps, one module each.

``friction_models()`` finds every module of this package, so a new law is one new
module with a ``FrictionModel`` subclass that names its ``cli_name``.
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import FrictionModel, registered
from .bouc_wen import BoucWen
from .dahl import Dahl
from .elasto_plastic import ElastoPlastic
from .gms import GMS
from .lugre import LuGre
from .static import CoulombViscous, StaticMap, StribeckMap

__all__ = ["GMS", "BoucWen", "CoulombViscous", "Dahl", "ElastoPlastic", "FrictionModel", "LuGre",
           "StaticMap", "StribeckMap", "friction_models"]


#: the paper's law, listed first
DEFAULT = "lugre"


def friction_models() -> dict[str, type[FrictionModel]]:
    """Command-line name -> friction law class, for every law module of this package
    (the default first, then in the order the modules define them)."""
    for module in sorted(m.name for m in pkgutil.iter_modules(__path__)):
        importlib.import_module(f"{__name__}.{module}")
    laws = registered()
    return {DEFAULT: laws.pop(DEFAULT), **laws}


friction_models()  # every law module declares its parameters on import (the catalogue)
