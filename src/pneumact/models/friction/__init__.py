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
           "StaticMap", "StribeckMap", "friction_law", "friction_models"]


#: the paper's law, listed first
DEFAULT = "lugre"


def friction_models() -> dict[str, type[FrictionModel]]:
    """Command-line name -> friction law class, for every law module of this package
    (the default first, then in the order the modules define them)."""
    for module in sorted(m.name for m in pkgutil.iter_modules(__path__)):
        importlib.import_module(f"{__name__}.{module}")
    laws = registered()
    return {DEFAULT: laws.pop(DEFAULT), **laws}


def friction_law(spec: str | FrictionModel) -> FrictionModel:
    """A law from its command-line name, with GMS's number of blocks after a colon
    ("lugre", "elasto-plastic", "gms:4"); a law instance is returned as it is."""
    from ...errors import ParameterError

    if isinstance(spec, FrictionModel):
        return spec
    laws = friction_models()
    name, _, count = str(spec).strip().partition(":")
    if name not in laws:
        raise ParameterError(f"friction law {spec!r}: unknown; allowed: {', '.join(laws)} "
                             "(gms:N for N blocks)")
    if not count:
        return laws[name]()
    if laws[name] is not GMS or not count.isdigit():
        raise ParameterError(f"friction law {spec!r}: only gms takes a number of blocks "
                             "(gms:4)")
    return GMS(n_elements=int(count))


def _declare_kind() -> None:
    """The kind ``friction``: the parameters of every law that may be placed beside
    another (``placed_laws``), under their own names, so that a model placing laws as
    instances (``friction_piston.Fc``) reads each with its law's catalogue entry."""
    from ...core.component import Block
    from ...parameters.catalogue import declare_kind, declared

    names = dict.fromkeys(name for law in registered().values()
                          if isinstance(law.block, Block) and law.placed_alone is None
                          for name in law.block.parameters)
    declare_kind("friction", *(declared(name) for name in names))


friction_models()  # every law module declares its parameters on import (the catalogue)
_declare_kind()
