"""Identification: parameters of an actuator or a friction law from measured records.

- ``identify_paper``: the paper's staged procedure (section III.2) on bench records;
- ``fit``: any parameters of any model fitted to one or several records (forward
  sensitivities as the Jacobian, shared or per-record parameters, multistart, profile
  likelihood);
- ``inverse_friction``: friction laws from measured motion and force (IDIM-LS);
- ``synthetic_campaign`` / ``paper_campaign``: bench tests for the procedure, simulated
  with realistic measurement noise.
"""

from .campaign import BenchTest, Noise, paper_campaign, synthetic_campaign
from .estimates import Estimates, linear_least_squares
from .fit import FitResult, Profile, experiment_for, fit
from .inverse import InverseFriction, inverse_friction
from .paper import PaperIdentification, StageResult, identify_paper, record_kind

__all__ = [
    "BenchTest",
    "Estimates",
    "FitResult",
    "InverseFriction",
    "Noise",
    "PaperIdentification",
    "Profile",
    "StageResult",
    "experiment_for",
    "fit",
    "identify_paper",
    "inverse_friction",
    "linear_least_squares",
    "paper_campaign",
    "record_kind",
    "synthetic_campaign",
]
